"""A subprocess adapter that makes one newcomer's mistake, the one its MODE names, and is otherwise the reference codec
(hostile_adapter's answers): what adapter-check must catch and explain.

``python wrong_adapter.py MODE``: ``reference`` (no mistake), ``wrong-rule`` (names crc on every refusal, as an
adapter reading "CRC" in an error text would), ``negative-zero`` (−0.0 written as 0), ``nan-widened`` (an fp32 NaN
written with the bits of the double it was widened to), ``missing-header`` (decoded messages without dst_ent),
``header-required`` (fails on an encode request whose header lacks a field), ``out-of-order-batch`` (answers a batch
with the right ids in the wrong places), ``no-name`` (a hello without implementation), ``unflushed`` (stdout never
flushed until the end), ``log-on-stdout`` (a log line among the answers), ``unknown-op`` (an unknown op answered as
an adapter failure), ``internal-on-accept`` (an accepted frame of an unknown id answered as an adapter failure),
``nothing`` (an unmodified starter: every request but hello answered unsupported; no mistake, nothing implemented),
``silent`` (reads every request, answers none, exits at the end of its input), ``long-hello`` (answers hello with a
line over the 1 MB the suite reads, then waits for the end of its input), ``ignores-eof`` (right, but goes on running
once its input ends), ``npe-on-null`` (its implementation throws on an inline message field or a list element holding none,
encoding or decoding, and the adapter answers that "internal", as a Java adapter catching every RuntimeException the
same way would).
"""

from __future__ import annotations

import json
import os
import struct
import sys
import time

from hostile_adapter import DEFS, answer as reference_answer

MODE = sys.argv[1]


def rewrite(value, change):
    """``value`` with ``change`` applied to every leaf (decoded forms are shallow: recursion is fine here)."""
    if isinstance(value, dict):
        return {k: rewrite(v, change) for k, v in value.items()}
    if isinstance(value, list):
        return [rewrite(v, change) for v in value]
    return change(value)


def holds_null(value) -> bool:
    """Whether a decoded form holds a null anywhere (an inline message field, or a list element, holding none)."""
    if isinstance(value, dict):
        return any(holds_null(v) for v in value.values())
    if isinstance(value, list):
        return any(holds_null(v) for v in value)
    return value is None


def widened(value):
    """An fp32 NaN's text as a writer that widened it to a double puts it: the double's 16-digit bits."""
    if isinstance(value, str) and value.startswith("nan:") and len(value) == 12:
        double = struct.unpack("<d", struct.pack("<d", struct.unpack("<f", struct.pack("<I", int(value[4:], 16)))[0]))[0]
        return f"nan:{struct.unpack('<Q', struct.pack('<d', double))[0]:016x}"
    return value


def answer(request: dict) -> dict:
    if MODE == "nothing" and request.get("op") != "hello":
        return {"id": request["id"], "ok": False, "unsupported": True, "error": "not implemented yet"}
    if MODE == "unknown-op" and request.get("op") not in ("hello", "encode", "decode"):
        return {"id": request["id"], "ok": False, "internal": True, "error": f"KeyError: {request.get('op')!r}"}
    if MODE == "npe-on-null" and request.get("op") == "encode" and holds_null(request["message"]):
        return {"id": request["id"], "ok": False, "internal": True, "error": "java.lang.NullPointerException"}
    if MODE == "header-required" and request.get("op") == "encode" and len(request["message"].get("header", {})) < 5:
        return {"id": request["id"], "ok": False, "internal": True, "error": "KeyError: 'timestamp'"}
    reply = reference_answer(request)
    if MODE == "npe-on-null" and request.get("op") == "decode" and holds_null(reply.get("message")):
        return {"id": request["id"], "ok": False, "internal": True, "error": "java.lang.NullPointerException"}
    if request.get("op") == "hello":
        if MODE == "no-name":
            del reply["implementation"]
        if MODE == "out-of-order-batch":
            reply["batch"] = True
    if MODE == "wrong-rule" and reply.get("ok") is False and not reply.get("unsupported"):
        reply["rule"] = "crc"
    if MODE == "internal-on-accept" and reply.get("rule") == "unknown-id":
        reply = {"id": request["id"], "ok": False, "internal": True, "error": "no message class for id 999"}
    message = reply.get("message")
    if isinstance(message, dict):
        if MODE == "negative-zero":
            reply["message"] = rewrite(message, lambda v: 0 if isinstance(v, float) and v == 0 else v)
        elif MODE == "nan-widened":
            reply["message"] = rewrite(message, widened)
        elif MODE == "missing-header":
            message["header"].pop("dst_ent", None)
    return reply


def main() -> None:
    assert DEFS  # the reference codec's definitions, loaded
    # PYTHONUNBUFFERED may be set: the unflushed mode buffers its output itself, as a C program's stdio does on a pipe
    out = os.fdopen(os.dup(1), "w", buffering=1 << 16) if MODE == "unflushed" else sys.stdout
    for line in sys.stdin:
        request = json.loads(line)
        if MODE == "silent":
            continue
        if MODE == "long-hello" and request.get("op") == "hello":
            out.write(json.dumps({**answer(request), "implementation": "x" * (1 << 21)}) + "\n")
            out.flush()
            continue
        if isinstance(request, list):  # a batch: the answers computed in reverse, numbered in order
            replies = [answer(r) for r in reversed(request)]
            for reply, r in zip(replies, request):
                reply["id"] = r["id"]
            out.write(json.dumps(replies) + "\n")
        else:
            if MODE == "log-on-stdout":
                out.write(f"INFO handling {request.get('op')}\n")
            out.write(json.dumps(answer(request)) + "\n")
        if MODE != "unflushed":
            out.flush()
    if MODE == "ignores-eof":
        time.sleep(600)  # adapter-check kills it (its process group) once it has seen it wait


if __name__ == "__main__":
    main()
