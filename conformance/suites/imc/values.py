"""The corpus's canonical value forms (the "decoded form") and their wire counterparts.

Floats are exact: the shortest decimal that round-trips at the field's width, ``-0.0`` with its
sign, ``"nan"``, ``"inf"``, ``"-inf"`` as strings, and ``"nan:<bits>"`` (IEEE bits in hex) for a
NaN whose payload is not the default quiet NaN. Plaintext is a string when every byte is ASCII,
else ``{"hex": ...}``; rawdata is lowercase hex.
"""

from __future__ import annotations

import math
import struct

DEFAULT_NAN = {4: 0x7FC00000, 8: 0x7FF8000000000000}
_BITS = {4: "I", 8: "Q"}
_FLOAT = {4: "f", 8: "d"}


def shortest_float(x: float, width: int) -> float:
    """The float whose repr is the shortest decimal that round-trips ``x`` at ``width`` bytes."""
    if width == 8 or not math.isfinite(x) or x == 0:
        return x
    for digits in range(1, 10):
        candidate = float(f"{x:.{digits}g}")
        try:
            if struct.unpack("<f", struct.pack("<f", candidate))[0] == x:
                return candidate
        except OverflowError:  # the rounded decimal lies beyond FLT_MAX
            continue
    raise AssertionError(f"no round-trip decimal for {x!r}")  # unreachable: 9 digits always suffice


def float_from_bits(bits: int, width: int):
    """Canonical JSON value of the IEEE float with the given bit pattern."""
    x = struct.unpack("<" + _FLOAT[width], struct.pack("<" + _BITS[width], bits))[0]
    if math.isnan(x):
        return "nan" if bits == DEFAULT_NAN[width] else f"nan:{bits:0{2 * width}x}"
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    return shortest_float(x, width)


def float_to_bits(value, width: int) -> int:
    """IEEE bit pattern of a canonical float value; raises ValueError if it is not one or overflows."""
    if isinstance(value, str):
        if value == "nan":
            return DEFAULT_NAN[width]
        if value.startswith("nan:"):
            bits = int(value[4:], 16)
            if bits >> (8 * width) or not math.isnan(struct.unpack("<" + _FLOAT[width], struct.pack("<" + _BITS[width], bits))[0]):
                raise ValueError(f"{value!r} is not a {8 * width}-bit NaN")
            return bits
        if value in ("inf", "-inf"):
            value = float(value)
        else:
            raise ValueError(f"{value!r} is not a float value")
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{value!r} is not a float value")
    try:
        packed = struct.pack("<" + _FLOAT[width], value)
    except OverflowError as exc:
        raise ValueError(f"{value!r} overflows a {8 * width}-bit float") from exc
    return struct.unpack("<" + _BITS[width], packed)[0]


def text_value(raw: bytes):
    """Canonical form of plaintext bytes."""
    return raw.decode("ascii") if raw.isascii() else {"hex": raw.hex()}


def text_bytes(value) -> bytes:
    """Bytes of a plaintext value: a string stands for its UTF-8 encoding, ``{"hex"}`` for raw bytes."""
    if isinstance(value, str):
        return value.encode("utf-8")
    if isinstance(value, dict) and set(value) == {"hex"}:
        return bytes.fromhex(value["hex"])
    raise ValueError(f"{value!r} is not a plaintext value")


def raw_bytes(value) -> bytes:
    if not isinstance(value, str):
        raise ValueError(f"{value!r} is not rawdata hex")
    return bytes.fromhex(value)
