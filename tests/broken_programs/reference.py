"""A correct subprocess adapter over the reference codec; each broken program is this with one bug.

``python reference.py [TRIGGER]``: TRIGGER is the hex of a frame; a broken program misbehaves when
asked to decode exactly that frame (``serve(bug)``) and answers everything else correctly.
"""

from __future__ import annotations

import json
import sys

from imc_conformance import codec
from imc_conformance.definitions import load_definitions

DEFS = load_definitions()


def answer(request: dict) -> dict:
    """The correct answer to one request, with its ``id``."""
    reply = {"id": request["id"], "ok": True}
    try:
        if request["op"] == "hello":
            reply.update(implementation="reference codec", suites=["imc"], byte_orders=["le", "be"])
        elif request["op"] == "encode":
            reply["frame"] = codec.encode(DEFS, request["message"], request["byte_order"]).hex()
        else:
            reply["message"] = codec.decode(DEFS, bytes.fromhex(request["frame"]))
    except (codec.EncodeError, codec.FrameError) as exc:
        reply = {"id": request["id"], "ok": False, "error": str(exc), "rule": exc.rule}
    return reply


def serve(bug=None) -> None:
    """Answer every request line; ``bug(reply) -> line`` replaces the answer to decoding the trigger frame."""
    trigger = sys.argv[1] if len(sys.argv) > 1 else None
    for line in sys.stdin:
        request = json.loads(line)
        reply = answer(request)
        is_trigger = request.get("op") == "decode" and request.get("frame") == trigger
        sys.stdout.write((bug(reply) if bug and is_trigger else json.dumps(reply)) + "\n")
        sys.stdout.flush()


if __name__ == "__main__":
    serve()
