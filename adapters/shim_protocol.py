"""The JSON-lines protocol loop shared by the subprocess shims (standard library only).

A shim provides an object with ``hello()``, ``encode(suite, message, byte_order) -> bytes`` and
``decode(suite, frame) -> dict``, raising ``Refused`` or ``Unsupported``; ``serve`` does the rest, batches
included (its hello says ``"batch": true``: a line may hold an array of requests, answered by an array).
It imports nothing from imc_conformance, so the shims stay independent of the suite's own code.
"""

from __future__ import annotations

import json
import math
import os
import struct
import sys

DEFAULT_NAN = {4: 0x7FC00000, 8: 0x7FF8000000000000}
_DECODE = json.JSONDecoder().decode  # made once: json.loads and json.dumps build them again at every call
_ENCODE = json.JSONEncoder(separators=(",", ":"), allow_nan=False).encode
FLOAT = {4: (struct.Struct("<f"), struct.Struct("<I")), 8: (struct.Struct("<d"), struct.Struct("<Q"))}


class Refused(Exception):
    """The implementation refused the input; ``rule`` names the corpus rule when the refusal says which."""

    def __init__(self, reason: str, rule: str | None = None):
        super().__init__(reason)
        self.reason, self.rule = reason, rule


class Unsupported(Exception):
    """The capability is absent (a byte order, a suite, a message)."""


def float_bits(text: str, width: int) -> int:
    """IEEE bits of a float written as a string: ``nan``, ``nan:<hex>``, ``inf``, ``-inf`` (else ValueError)."""
    if text == "nan":
        return DEFAULT_NAN[width]
    as_float, as_bits = FLOAT[width]
    if text.startswith("nan:"):
        bits = int(text[4:], 16)
        if bits >> (8 * width) or not math.isnan(as_float.unpack(as_bits.pack(bits))[0]):
            raise ValueError(f"{text!r} is not a {8 * width}-bit NaN")
        return bits
    if text in ("inf", "-inf"):
        return as_bits.unpack(as_float.pack(float(text)))[0]
    raise ValueError(f"{text!r} is not a float value")


def float_value(x: float, width: int):
    """The decoded form of a float at ``width`` bytes: a number, or a string for NaN and infinities."""
    as_float, as_bits = FLOAT[width]
    bits = as_bits.unpack(as_float.pack(x))[0]
    x = as_float.unpack(as_bits.pack(bits))[0]
    if math.isnan(x):
        return "nan" if bits == DEFAULT_NAN[width] else f"nan:{bits:0{2 * width}x}"
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    return x


MAX_ANSWER_LINE = 1_000_000  # the longest answer line the suite reads (adapters/README.md)


def perform(shim, request: dict) -> dict:
    op = request.get("op")
    if op == "hello":
        return {**shim.hello(), "batch": True}
    if op == "encode":
        return {"frame": shim.encode(request.get("suite"), request.get("message"), request.get("byte_order")).hex()}
    if op == "decode":
        return {"message": shim.decode(request.get("suite"), bytes.fromhex(request["frame"]))}
    raise Unsupported(f"operation {op!r}")


def respond(shim, line: bytes) -> str:
    """The answer line to one request line (one request, or a batch: a JSON array of requests, answered with an
    array of answers); a failure of the shim itself is ``internal``."""
    try:
        request = _DECODE(line.decode("utf-8"))
    except ValueError as exc:
        return json.dumps({"id": None, "ok": False, "internal": True, "error": f"not JSON: {exc}"})
    if isinstance(request, list):
        answers = [answer(shim, r) for r in request]
        if sum(len(a) + 1 for a in answers) + 2 > MAX_ANSWER_LINE:  # the contract's bound: one answer per line then
            return "\n".join(answers)
        return "[" + ",".join(answers) + "]"
    return answer(shim, request)


def answer(shim, request) -> str:
    """The answer to one request, as JSON text."""
    ident = None
    try:
        ident = request["id"]
        reply = {"id": ident, "ok": True, **perform(shim, request)}
    except Refused as exc:
        reply = {"id": ident, "ok": False, "error": exc.reason, **({"rule": exc.rule} if exc.rule else {})}
    except Unsupported as exc:
        reply = {"id": ident, "ok": False, "unsupported": True, "error": str(exc)}
    except Exception as exc:
        reply = {"id": ident, "ok": False, "internal": True, "error": f"{type(exc).__name__}: {exc}"}
    try:
        return _ENCODE(reply)
    except ValueError as exc:
        return json.dumps({"id": ident, "ok": False, "internal": True, "error": f"unserialisable answer: {exc}"})


def protocol_stdout():
    """The real stdout for answers; fd 1 and ``sys.stdout`` become stderr so stray prints cannot corrupt it."""
    out = os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)
    sys.stdout = sys.stderr
    return out


def serve(make_shim) -> int:
    """Protect stdout, build the shim (``make_shim()``), then answer every request line until stdin closes."""
    out = protocol_stdout()
    shim = make_shim()
    for line in sys.stdin.buffer:
        out.write(respond(shim, line).encode() + b"\n")
        out.flush()
    return 0
