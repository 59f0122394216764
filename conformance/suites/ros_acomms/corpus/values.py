"""Field values built from the definitions alone: defaults, distinctive filled values, and the valid and
acceptable variants of each field."""

from __future__ import annotations

from ....kinds.vector.floats import FLOAT_CLASSES, PAYLOAD_NANS
from ..codec import int_bounds, int_form
from ..definitions import PRIMITIVES, Edition, FieldType

# Distinctive, in-range values by type (bytes that are easy to spot in a hex dump).
FILLED_INTS = {"int8": -5, "uint8": 42, "int16": -1234, "uint16": 4660, "int32": -123456, "uint32": 305419896,
               "int64": -1234567890123, "uint64": 1234567890123}
FILLED = {"bool": True, "float32": 1.5, "float64": 0.25, "string": "ros", "time": {"secs": 1700000000, "nsecs": 500000000},
          "duration": {"secs": -2, "nsecs": 250000000}}
PRINTABLE = "".join(chr(c) for c in range(0x20, 0x7F))
TEXTS = {"printable-ascii": PRINTABLE, "utf8": "ol\u00e1 \u2014 \u6c34 \U0001f30a", "control": "\x00\t\n\r\x1b\x7f",
         "long": (PRINTABLE * 11)[:1000]}
TIMES = {"zero": {"secs": 0, "nsecs": 0}, "max": {"secs": 0xFFFFFFFF, "nsecs": 999999999},
         "max-signed-secs": {"secs": 0x7FFFFFFF, "nsecs": 999999999}, "typical": {"secs": 1700000000, "nsecs": 123456789}}
DURATIONS = {"zero": {"secs": 0, "nsecs": 0}, "negative": {"secs": -1, "nsecs": -500000000},
             "min": {"secs": -0x80000000, "nsecs": -999999999}, "max": {"secs": 0x7FFFFFFF, "nsecs": 999999999}}


def default(edition: Edition, t: FieldType):
    if t.array is not None:
        if t.base == "uint8":
            return "" if t.array < 0 else "00" * t.array
        return [] if t.array < 0 else [default(edition, t.element) for _ in range(t.array)]
    if t.base == "bool":
        return False
    if t.base in ("float32", "float64"):
        return 0.0
    if t.base in PRIMITIVES:
        return 0
    if t.base == "string":
        return ""
    if t.base in ("time", "duration"):
        return {"secs": 0, "nsecs": 0}
    return fields(edition, t.base, default)


def filled(edition: Edition, t: FieldType):
    if t.array is not None:
        if t.base == "uint8":
            return "c0ffee" if t.array < 0 else "a5" * t.array
        one = filled(edition, t.element)
        return [one] if t.array < 0 else [one] * t.array
    if t.base in FILLED_INTS:
        return int_form(FILLED_INTS[t.base])
    if t.base in FILLED:
        return FILLED[t.base]
    return fields(edition, t.base, filled)


def fields(edition: Edition, full: str, make) -> dict:
    return {f.name: make(edition, f.type) for f in edition[full].fields}


def variants(edition: Edition, t: FieldType):
    """(path, value, tags) of each valid variant of a field of type ``t`` (its default is the minimal case)."""
    base = t.base
    if t.array is not None:
        if base == "uint8" and t.array < 0:
            yield "all-bytes", bytes(range(256)).hex(), ["class:all-bytes"]
            yield "long", "5a" * 4096, ["class:long"]
        elif t.array < 0:
            one, other = filled(edition, t.element), default(edition, t.element)
            yield "one", [one], ["class:one"]
            yield "many", [one, other, one], ["class:many"]
            yield "hundred", [one] * 100, ["class:long"]
        elif base == "bool":
            yield "all-true", [True] * t.array, ["class:all"]
            yield "mixed", [i % 2 == 0 for i in range(t.array)], ["class:mixed"]
        else:
            yield "filled", filled(edition, t), ["class:filled"]
        return
    if base == "bool":
        yield "true", True, ["class:true"]
    elif base in ("float32", "float64"):
        width = PRIMITIVES[base][1]
        for name, values in FLOAT_CLASSES.items():
            yield name, values[0 if width == 4 else 1], [f"class:{name}"]
    elif base in PRIMITIVES:
        lo, hi = int_bounds(base)
        classes = {"min": lo, "max": hi, "one": 1} | ({"minus-one": -1} if lo < 0 else {})
        for name, value in classes.items():
            yield name, int_form(value), [f"class:{name}"]
    elif base == "string":
        for name, text in TEXTS.items():
            yield name, text, [f"class:{name}"]
    elif base == "time":
        for name, value in TIMES.items():
            if name != "zero":
                yield name, value, [f"class:{name}"]
    elif base == "duration":
        for name, value in DURATIONS.items():
            if name != "zero":
                yield name, value, [f"class:{name}"]
    else:
        yield "filled", filled(edition, t), ["class:filled"]


def pins_nan(tags: list[str]) -> bool:
    return bool(PAYLOAD_NANS & set(tags))
