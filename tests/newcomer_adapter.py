"""A subprocess adapter as newcomers write them, over the reference codec: one way of going wrong per MODE, each
either the adapter's mistake or the implementation's own result, which adapter-check must tell apart.

``python newcomer_adapter.py MODE``:
``bare-nan`` (a codec of Heartbeat and LblRange only, every other message answered "unsupported"; the adapter turns
the decoded form's "nan" and "inf" into Python floats and writes them with ``json.dumps``: bare NaN and Infinity, not
JSON); ``unsupported-refusals`` (decodes every valid frame, and answers every refusal "unsupported": the adapter
calls the capability absent); ``crc-at-end`` (the implementation's transport checks the CRC on the datagram's last two
bytes, not the frame's footer: a frame with bytes after it is refused naming crc; the adapter reports it faithfully);
``hang-on-negative-zero`` and ``crash-on-negative-zero`` (the implementation hangs, or the process dies, decoding a
frame holding −0.0; the adapter is right).
"""

from __future__ import annotations

import json
import os
import sys
import time

from hostile_adapter import DEFS, answer as reference_answer
from imc_conformance.suites.imc import codec

MODE = sys.argv[1]
IMPLEMENTED = {"Heartbeat", "LblRange"}


def native(value):
    """The decoded form with its NaN and infinity words as Python floats (what a newcomer's codec binding returns)."""
    if isinstance(value, dict):
        return {k: native(v) for k, v in value.items()}
    if isinstance(value, list):
        return [native(v) for v in value]
    if isinstance(value, str) and (value == "nan" or value.startswith("nan:")):
        return float("nan")
    if value in ("inf", "-inf"):
        return float(value)
    return value


def holds_negative_zero(value) -> bool:
    if isinstance(value, dict):
        return any(holds_negative_zero(v) for v in value.values())
    if isinstance(value, list):
        return any(holds_negative_zero(v) for v in value)
    return isinstance(value, float) and value == 0 and str(value).startswith("-")


def answer(request: dict) -> dict:
    op = request.get("op")
    if op == "hello":
        return reference_answer(request) | {"implementation": f"newcomer codec ({MODE})"}
    if MODE == "crc-at-end" and op == "decode":
        frame = bytes.fromhex(request["frame"])
        size = int.from_bytes(frame[4:6], "little" if frame[:2] == b"\x54\xfe" else "big") if len(frame) >= 6 else 0
        if len(frame) > 20 + size + 2:  # bytes after the footer: the datagram's last two bytes are no CRC of it
            return {"id": request["id"], "ok": False, "error": "CRC mismatch", "rule": "crc"}
    reply = reference_answer(request)
    message = reply.get("message")
    if MODE in ("hang-on-negative-zero", "crash-on-negative-zero") and holds_negative_zero(message):
        if MODE.startswith("crash"):
            os._exit(3)
        time.sleep(3600)
    if MODE == "unsupported-refusals" and reply.get("ok") is False:
        return {"id": request["id"], "ok": False, "unsupported": True, "error": "not supported"}
    if MODE == "bare-nan":
        abbrev = message["abbrev"] if message else request.get("message", {}).get("abbrev")
        if op in ("encode", "decode") and abbrev is not None and abbrev not in IMPLEMENTED:
            return {"id": request["id"], "ok": False, "unsupported": True, "error": f"{abbrev} is not implemented"}
        if message is not None:
            reply["message"] = native(message)
    return reply


def main() -> None:
    assert DEFS and codec
    for line in sys.stdin:
        request = json.loads(line)
        if isinstance(request, list):
            sys.stdout.write(json.dumps([answer(r) for r in request]) + "\n")
        else:
            sys.stdout.write(json.dumps(answer(request)) + "\n")
        sys.stdout.flush()


if __name__ == "__main__":
    main()
