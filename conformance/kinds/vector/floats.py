"""Floats in the decoded form, shared by every suite: exact values and the comparison policy.

A float is the shortest decimal that round-trips at the field's width (parse fp32 values as fp32), ``-0.0``
keeps its sign, ``"nan"`` is the default quiet NaN, ``"inf"`` and ``"-inf"`` the infinities, and
``"nan:<bits>"`` (IEEE bits in hex) a NaN with any other bit pattern. Floats compare by their bits at the
field's width; any NaN equals any NaN unless a case pins NaN payloads.
"""

from __future__ import annotations

import math
import struct

DEFAULT_NAN = {4: 0x7FC00000, 8: 0x7FF8000000000000}
_BITS = {4: "I", 8: "Q"}
_FLOAT = {4: "f", 8: "d"}


F32_MAX = struct.unpack("<f", struct.pack("<I", 0x7F7FFFFF))[0]
F32_SUB_MIN = struct.unpack("<f", struct.pack("<I", 0x00000001))[0]
F32_SUB_MAX = struct.unpack("<f", struct.pack("<I", 0x007FFFFF))[0]
F32_NORM_MIN = struct.unpack("<f", struct.pack("<I", 0x00800000))[0]
F64_SUB_MIN = struct.unpack("<d", struct.pack("<Q", 1))[0]
F64_SUB_MAX = struct.unpack("<d", struct.pack("<Q", 0x000FFFFFFFFFFFFF))[0]

# Boundary classes of a float field, for generators: name -> value per width (4, 8). Non-finite ones are
# only valid where the field has no declared range.
FLOAT_CLASSES = {
    "zero": (0.0, 0.0),
    "negative-zero": (-0.0, -0.0),
    "max-finite": (F32_MAX, 1.7976931348623157e308),
    "min-finite": (-F32_MAX, -1.7976931348623157e308),
    "min-subnormal": (F32_SUB_MIN, F64_SUB_MIN),
    "max-subnormal": (F32_SUB_MAX, F64_SUB_MAX),
    "negative-min-subnormal": (-F32_SUB_MIN, -F64_SUB_MIN),
    "min-normal": (F32_NORM_MIN, 2.2250738585072014e-308),
    "nan": ("nan", "nan"),
    "inf": ("inf", "inf"),
    "negative-inf": ("-inf", "-inf"),
    "nan-payload": ("nan:7fc00001", "nan:7ff8000000000001"),
    "negative-nan": ("nan:ffc00000", "nan:fff8000000000000"),
}
NON_FINITE = ("nan", "inf", "negative-inf", "nan-payload", "negative-nan")
PAYLOAD_NANS = {"class:nan-payload", "class:negative-nan"}  # cases about a NaN's exact bits
SHORTEST_CACHE = 1 << 16  # fp32 values whose shortest decimal is remembered (a capture repeats its values)
_SHORTEST32: dict[float, float] = {}
_F32 = struct.Struct("<f")


def shortest_float(x: float, width: int) -> float:
    """The float whose repr is the shortest decimal that round-trips ``x`` at ``width`` bytes."""
    if width == 8 or not math.isfinite(x) or x == 0:
        return x
    found = _SHORTEST32.get(x)
    if found is None:
        if len(_SHORTEST32) >= SHORTEST_CACHE:
            _SHORTEST32.clear()
        found = _SHORTEST32[x] = _shortest32(x)
    return found


def _shortest32(x: float) -> float:
    for digits in range(1, 10):
        candidate = float(f"{x:.{digits}g}")
        try:
            if _F32.unpack(_F32.pack(candidate))[0] == x:
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


def as_float(value) -> float:
    """A decoded-form float as a Python float (every NaN form is a NaN)."""
    return float(value.split(":")[0]) if isinstance(value, str) else float(value)


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


def same_float(expected, actual, width: int, nan_payload: bool) -> bool:
    """Whether an answered float equals the expected one at ``width`` bytes, as the policy above says."""
    if type(expected) is float and type(actual) is float and expected == actual and expected != 0.0:
        return True  # the common case: equal finite non-zero values (zeros still need their sign compared)
    try:
        a = float_to_bits(actual, width)
    except ValueError:
        return False
    e = float_to_bits(expected, width)
    if not nan_payload and is_nan(e, width) and is_nan(a, width):
        return True
    return a == e


def is_nan(bits: int, width: int) -> bool:
    """Whether an IEEE bit pattern of ``width`` bytes is a NaN."""
    exp_mask, frac_mask = ((0x7F800000, 0x007FFFFF) if width == 4 else (0x7FF0000000000000, 0x000FFFFFFFFFFFFF))
    return bits & exp_mask == exp_mask and bool(bits & frac_mask)

