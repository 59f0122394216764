"""Answers the trigger frame's decode with ``ok: true`` but no message."""

import json

from reference import serve

serve(lambda reply: json.dumps({"id": reply["id"], "ok": True}))
