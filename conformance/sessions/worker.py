"""A library adapter in a process of its own, speaking the subprocess protocol of adapters/README.md (batches
included): how ``imc-conformance fuzz`` runs an in-process implementation, so that a segfault or hang of it is a
finding (CRASH, TIMEOUT, with the input that caused it) and not the end of the fuzzer.

``python -m imc_conformance.sessions.worker --suite SUITE ADAPTER [NAME=VALUE ...]``: ADAPTER as ``--adapter`` takes
it (a built-in name, ``module:attribute`` or ``file.py:attribute``), NAME=VALUE as ``--adapter-arg``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import struct
import sys

from ..adapter_api import Rejected, Unsupported

_ENCODE = json.JSONEncoder(separators=(",", ":"), allow_nan=False).encode
ENVELOPE = ("id", "op", "suite", "frame", "message")


def perform(adapter, param: str, request: dict) -> dict:
    op, suite = request.get("op"), request.get("suite")
    rest = {k: v for k, v in request.items() if k not in ENVELOPE}
    if op == "hello":
        return {**adapter.hello(), "batch": True}
    if op == "encode":
        return {"frame": bytes(adapter.encode(suite, request.get("message"), rest.pop(param, None))).hex()}
    if op == "decode":
        return {"message": adapter.decode(suite, bytes.fromhex(request["frame"]), **rest)}
    if op == "describe" and hasattr(adapter, "describe"):
        return dict(adapter.describe(suite, **rest))
    raise Unsupported(f"unknown op {op!r}")


def answer(adapter, param: str, request) -> str:
    ident = request.get("id") if isinstance(request, dict) else None
    try:
        reply = {"id": ident, "ok": True, **perform(adapter, param, request)}
    except Rejected as exc:
        reply = {"id": ident, "ok": False, "error": exc.reason, **({"rule": exc.rule} if exc.rule else {})}
    except Unsupported as exc:
        reply = {"id": ident, "ok": False, "unsupported": True, "error": str(exc)}
    except Exception as exc:  # the adapter's own failure: ADAPTER_ERROR, never a pass
        reply = {"id": ident, "ok": False, "internal": True, "error": f"{type(exc).__name__}: {exc}"}
    try:
        return _ENCODE(reply)
    except ValueError:  # a NaN or infinity, which a library adapter may return as a Python float
        reply = non_finite_as_text(reply)
    except TypeError:
        pass
    try:
        return _ENCODE(reply)
    except (TypeError, ValueError) as exc:
        return _ENCODE({"id": ident, "ok": False, "internal": True, "error": f"unserialisable answer: {exc}"})


def non_finite_as_text(value):
    """``value`` with every non-finite float in the decoded form's words: "inf", "-inf", "nan" for the default quiet
    NaN (the same at either width), "nan:<16 hex digits>" for any other (exact for a fp64 field; an fp32 field's
    payload is not known from a double). Iterative: no recursion an answer could drive."""
    out = [None]
    stack = [(value, out, 0)]
    while stack:
        item, parent, key = stack.pop()
        if isinstance(item, float) and not math.isfinite(item):
            bits = struct.unpack("<Q", struct.pack("<d", item))[0]
            item = ("inf" if item > 0 else "-inf") if math.isinf(item) else \
                "nan" if bits == 0x7FF8000000000000 else f"nan:{bits:016x}"
        elif isinstance(item, dict):
            copy = dict(item)
            stack.extend((v, copy, k) for k, v in item.items())
            item = copy
        elif isinstance(item, list):
            copy = list(item)
            stack.extend((v, copy, i) for i, v in enumerate(item))
            item = copy
        parent[key] = item
    return out[0]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m imc_conformance.sessions.worker", description=__doc__.splitlines()[0])
    parser.add_argument("--suite", required=True)
    parser.add_argument("adapter")
    parser.add_argument("arguments", nargs="*", metavar="NAME=VALUE")
    args = parser.parse_args(argv)
    out = os.fdopen(os.dup(1), "wb")  # answers only: stray prints of the implementation go to stderr
    os.dup2(2, 1)
    sys.stdout = sys.stderr
    from ..commands.adapters import load_library_adapter
    from ..errors import UsageError
    from ..suites import load_suite

    suite = load_suite(args.suite)
    try:
        adapter = load_library_adapter(args.adapter, suite, dict(a.partition("=")[::2] for a in args.arguments))
    except UsageError as exc:
        print(f"worker: {exc}", file=sys.stderr)
        return 2
    for line in sys.stdin.buffer:
        try:
            request = json.loads(line)
        except ValueError as exc:
            out.write(_ENCODE({"id": None, "ok": False, "internal": True, "error": f"not JSON: {exc}"}).encode() + b"\n")
            continue
        if isinstance(request, list):
            text = "[" + ",".join(answer(adapter, suite.encoding_param, r) for r in request) + "]"
        else:
            text = answer(adapter, suite.encoding_param, request)
        out.write(text.encode() + b"\n")
        out.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
