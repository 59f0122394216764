"""Answers the trigger frame's decode under an id that was never asked."""

import json

from reference import serve

serve(lambda reply: json.dumps({**reply, "id": reply["id"] + 1_000_000}))
