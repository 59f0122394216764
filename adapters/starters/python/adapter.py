"""A starter adapter for imc-conformance (the adapter contract: ADAPTER-CONTRACT.md beside this file when copied with
``imc-conformance adapter-kit python DIR``): the protocol loop on the standard library's json, answering every request
"unsupported" until the TODOs call your implementation, and the decoded form's values done right (floats by their
bits at the field's width: -0.0, NaN payloads, fp32 written with its own shortest digits; hex). With --values it reads
value probes instead (what the suite's tests check the helpers with). Run: python3 adapter.py
"""

import json
import math
import struct
import sys

DEFAULT_NAN = {4: 0x7FC00000, 8: 0x7FF8000000000000}
FORMATS = {4: ("f", "I"), 8: ("d", "Q")}  # struct codes: the float and the unsigned integer of its width


def main() -> None:
    values = sys.argv[1:] == ["--values"]
    for line in sys.stdin.buffer:  # lines of any length; the end of input is the end of the run
        if not line.strip():
            continue
        try:
            request = json.loads(line)
            if not isinstance(request, dict):
                raise ValueError("a request is a JSON object")
        except ValueError as exc:
            reply = {"id": None, "ok": False, "internal": True, "error": f"unreadable request: {exc}"}
        else:
            reply = value_probe(request) if values else answer(request)
        sys.stdout.write(json.dumps(reply, allow_nan=False) + "\n")
        sys.stdout.flush()


def answer(request: dict) -> dict:
    reply = {"id": request.get("id")}
    op = request.get("op")
    if op == "hello":
        reply.update(ok=True, implementation="my-imc 0.0.0 (starter: nothing implemented yet)",  # TODO: name, version
                     suites=["imc"], byte_orders=["le", "be"])  # TODO: the byte orders your implementation emits
        return reply
    try:
        if op == "encode":
            # TODO: build your message from request["message"] ("abbrev", "header", "fields"; read floats with
            # float_bits(value, 4 or 8)), serialize it in request["byte_order"] ("le" or "be"), and answer
            #   reply.update(ok=True, frame=frame.hex())
            # What the implementation's own call raises is its answer, not the adapter's bug: catch it around that
            # call only and refuse:  try: frame = codec.serialize(msg)  except Exception as exc: return refuse(reply, repr(exc))
            return unsupported(reply, "encode is not implemented yet")
        if op == "decode":
            # TODO: frame = bytes.fromhex(request["frame"]); deserialize it; answer
            #   reply.update(ok=True, message={"abbrev": ..., "header": {"timestamp": float_json(bits, 8), "src": ...,
            #                "src_ent": ..., "dst": ..., "dst_ent": ...}, "fields": {...}})
            # (floats with float_json(bits, 4 or 8), rawdata as hex). A refusal: refuse(reply, error, rule), with a rule
            # only when the check that refused is that rule's check.
            return unsupported(reply, "decode is not implemented yet")
    except Exception as exc:  # a failure of the adapter's own code (not of the implementation's call): ADAPTER_ERROR
        reply.update(ok=False, internal=True, error=f"adapter failed: {exc!r}")
        return reply
    return unsupported(reply, "unknown op")


def unsupported(reply: dict, why: str) -> dict:
    reply.update(ok=False, unsupported=True, error=why)
    return reply


def refuse(reply: dict, error: str, rule: str | None = None) -> dict:
    reply.update(ok=False, error=error)
    if rule:
        reply["rule"] = rule
    return reply


def float_json(bits: int, width: int):
    """The decoded form of the float of ``width`` bytes with these IEEE bits: a number (-0.0 keeps its sign, an fp32
    written with its own shortest digits), "inf", "-inf", "nan" (the default quiet NaN) or "nan:<hex bits>"."""
    real, whole = FORMATS[width]
    x = struct.unpack(">" + real, struct.pack(">" + whole, bits))[0]
    if math.isnan(x):  # never through a Python float: its payload is kept as the bits say
        return "nan" if bits == DEFAULT_NAN[width] else f"nan:{bits:0{2 * width}x}"
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    if width == 4 and x != 0:
        for digits in range(1, 10):  # the shortest decimal that reads back as this fp32
            shortest = float(f"{x:.{digits}g}")
            try:
                if struct.pack(">f", shortest) == struct.pack(">f", x):
                    return shortest
            except OverflowError:  # rounded up past the largest fp32
                continue
    return x


def float_bits(value, width: int) -> int:
    """The IEEE bits at ``width`` bytes of a decoded form's float (a number, "inf", "-inf", "nan" or "nan:<hex>");
    ValueError for anything else, or a number too large for the width."""
    real, whole = FORMATS[width]
    if isinstance(value, str):
        if value == "nan":
            return DEFAULT_NAN[width]
        if value.startswith("nan:"):
            return int(value[4:], 16)
        if value not in ("inf", "-inf"):
            raise ValueError(f"not a float: {value!r}")
        value = float(value)
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"not a float: {value!r}")
    try:
        return struct.unpack(">" + whole, struct.pack(">" + real, float(value)))[0]
    except OverflowError:
        raise ValueError(f"{value!r} is too large for a {8 * width}-bit float") from None


def value_probe(probe: dict) -> dict:
    """{"width": 4|8, "bits": hex} -> the value written and the bits read back from its JSON text; {"hex": ...} -> it,
    read and written again."""
    if "hex" in probe:
        try:
            return {"hex": bytes.fromhex(probe["hex"]).hex()}
        except ValueError as exc:
            return {"error": str(exc)}
    width, bits = probe["width"], int(probe["bits"], 16)
    value = float_json(bits, width)
    try:
        back = float_bits(json.loads(json.dumps(value)), width)
    except ValueError as exc:
        return {"value": value, "error": str(exc)}
    return {"value": value, "bits": f"{back:0{2 * width}x}"}


if __name__ == "__main__":
    main()
