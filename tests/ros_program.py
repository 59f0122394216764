"""A ROS subprocess adapter over the suite's reference codec: ``python ros_program.py [reference|allocates]``.

``allocates`` trusts the first length of every frame it decodes and allocates what it claims, as a naive
reader would: under the session's memory limit that kills it, instead of the machine.
"""

from __future__ import annotations

import json
import struct
import sys

from imc_conformance.suites.ros_acomms import mutants as ros_mutants

from imc_conformance.adapter_api import Rejected

MODE = sys.argv[1] if len(sys.argv) > 1 else "reference"
REFERENCE = ros_mutants.Reference()


def answer(request: dict) -> dict:
    op, ident = request.get("op"), request["id"]
    try:
        if op == "hello":
            return {"id": ident, "ok": True, **REFERENCE.hello()}
        if op == "encode":
            return {"id": ident, "ok": True, "frame": REFERENCE.encode("ros_acomms", request["message"], request["encoding"]).hex()}
        if op == "decode":
            frame = bytes.fromhex(request["frame"])
            if MODE == "allocates" and len(frame) >= 4:
                buffer = bytearray(max(struct.unpack_from("<I", frame, i)[0] for i in range(0, len(frame) - 3)) * 8)
                buffer[-1] = 1
            return {"id": ident, "ok": True, "message": REFERENCE.decode("ros_acomms", frame, request["type"], request["encoding"])}
        if op == "describe":
            return {"id": ident, "ok": True, **REFERENCE.describe("ros_acomms", request["type"])}
        return {"id": ident, "ok": False, "unsupported": True, "error": f"op {op!r}"}
    except Rejected as exc:
        return {"id": ident, "ok": False, "error": exc.reason, **({"rule": exc.rule} if exc.rule else {})}


for line in sys.stdin:
    sys.stdout.write(json.dumps(answer(json.loads(line))) + "\n")
    sys.stdout.flush()
