"""A subprocess adapter that does not work: it greets as the reference codec does, then answers every request as
its own failure ("internal": ADAPTER_ERROR), as an adapter whose every call into its library raises would."""

from __future__ import annotations

import json
import sys

from hostile_adapter import answer as reference_answer


def main() -> None:
    for line in sys.stdin:
        request = json.loads(line)
        if isinstance(request, list):
            reply = [{"id": r["id"], "ok": False, "internal": True, "error": "TypeError: broken"} for r in request]
        elif request.get("op") == "hello":
            reply = reference_answer(request)
        else:
            reply = {"id": request["id"], "ok": False, "internal": True, "error": "TypeError: broken"}
        sys.stdout.write(json.dumps(reply) + "\n")
        sys.stdout.flush()


if __name__ == "__main__":
    main()
