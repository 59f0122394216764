"""Reports an internal failure (``internal: true``) for the trigger frame's decode."""

import json

from reference import serve

serve(lambda reply: json.dumps({"id": reply["id"], "ok": False, "internal": True, "error": "KeyError: 'range'"}))
