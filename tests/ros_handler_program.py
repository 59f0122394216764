"""The reference service handler as a subprocess adapter: ``python ros_handler_program.py [BROKEN]``. It speaks
the handler operations of the adapter protocol (setup, call, publish), as a handler in another language would."""

from __future__ import annotations

import json
import sys

from imc_conformance.adapter_api import Rejected, Unsupported
from imc_conformance.suites.ros_acomms.handler import ReferenceHandler

HANDLER = ReferenceHandler(sys.argv[1] if len(sys.argv) > 1 else None)


def answer(request: dict) -> dict:
    op, ident = request.get("op"), request["id"]
    try:
        if op == "hello":
            return {"id": ident, "ok": True, **HANDLER.hello()}
        if op == "setup":
            HANDLER.setup(request["suite"], request["service"], request["state"])
            return {"id": ident, "ok": True}
        if op == "call":
            return {"id": ident, "ok": True, "response": HANDLER.call(request["suite"], request["service"], request["request"])}
        if op == "publish":
            HANDLER.publish(request["suite"], request["type"], request["message"])
            return {"id": ident, "ok": True}
        return {"id": ident, "ok": False, "unsupported": True, "error": f"op {op!r}"}
    except Rejected as exc:
        return {"id": ident, "ok": False, "error": exc.reason}
    except Unsupported as exc:
        return {"id": ident, "ok": False, "unsupported": True, "error": str(exc)}


for line in sys.stdin:
    sys.stdout.write(json.dumps(answer(json.loads(line))) + "\n")
    sys.stdout.flush()
