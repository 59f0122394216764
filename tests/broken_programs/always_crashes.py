"""Answers hello, then dies on every other request."""

import json
import os
import sys

for line in sys.stdin:
    request = json.loads(line)
    if request["op"] != "hello":
        os._exit(3)
    print(json.dumps({"id": request["id"], "ok": True, "implementation": "always crashes", "suites": ["imc"],
                      "byte_orders": ["le"]}), flush=True)
