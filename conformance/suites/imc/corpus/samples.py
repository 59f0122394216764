"""Generic message values built from the definitions alone: defaults, filled values, nesting."""

from __future__ import annotations

import copy
import struct

from ..definitions import Definitions, FieldDef, MessageDef

# The header of the corpus's ordinary frames (invalid and acceptable ones, promoted findings): every field given,
# none of them a value a case is about (a zero or -0.0 timestamp, a null address).
ORDINARY_HEADER = {"timestamp": 1700000000.5, "src": 0x001E, "src_ent": 42, "dst": 0x4101, "dst_ent": 7}
# Distinctive, in-range values by integer type (bytes that are easy to spot in a hex dump).
FILLED_INTS = {"uint8_t": 42, "int8_t": -5, "uint16_t": 4660, "int16_t": -1234, "uint32_t": 305419896,
               "int32_t": -123456, "int64_t": -1234567890123}


def default_value(f: FieldDef):
    """The zero of the field's type, or the bound of its min/max nearest zero; for an enum whose table lacks 0, its
    lowest value in every edition."""
    if f.enum_kind == "enum" and not any(v.value == 0 for v in f.enum_values):
        return min(v.value for v in f.enum_values if v.editions is None)
    if f.is_float:
        if in_float_range(f, 0.0):
            return 0.0
        return bound_inside(f, f.minimum, +1) if f.minimum is not None and f.minimum > 0 else bound_inside(f, f.maximum, -1)
    if f.is_int:
        lo, hi = f.int_range
        return min(max(0, lo), hi)
    return {"plaintext": "", "rawdata": "", "message": None, "message-list": []}[f.type]


def default_fields(mdef: MessageDef) -> dict:
    return {f.abbrev: default_value(f) for f in mdef.fields}


def message(abbrev: str, fields: dict, header: dict | None = None) -> dict:
    return {"abbrev": abbrev, "header": dict(header or {}), "fields": fields}


def inline(abbrev: str, fields: dict) -> dict:
    return {"abbrev": abbrev, "fields": fields}


def common_enum_values(defs: Definitions, f: FieldDef) -> list[int]:
    """Enum values defined in every edition, in table order."""
    return [v.value for v in f.enum_values if all(v.in_edition(e) for e in defs.editions)]


def filled_value(defs: Definitions, f: FieldDef, depth: int = 1):
    """A non-default value valid in every edition; inline values nest ``depth`` levels."""
    if f.enum_kind == "bitfield":
        bits = 0
        for v in f.enum_values:
            bits |= v.value
        return bits
    if f.enum_kind == "enum":
        values = common_enum_values(defs, f)
        return next((v for v in values if v != 0), values[0])
    if f.is_int:
        lo, hi = f.int_range
        return min(max(FILLED_INTS[f.type], lo), hi)
    if f.is_float:
        if f.minimum is not None or f.maximum is not None:
            return next((x for x in (0.5, -0.5) if in_float_range(f, x)), default_value(f))
        return 1.5 if f.type == "fp32_t" else 0.25
    if f.type == "plaintext":
        return "imc"
    if f.type == "rawdata":
        return "c0ffee"
    inner = inner_types(defs, f)[0]
    element = filled_inline(defs, inner, depth - 1) if depth > 0 else None
    if f.type == "message":
        return element
    return [element] if element is not None else []


def at_width(f: FieldDef, x: float) -> float:
    """``x`` as a float field of ``f``'s width holds it."""
    fmt = "<f" if f.size == 4 else "<d"
    return struct.unpack(fmt, struct.pack(fmt, x))[0]


def in_float_range(f: FieldDef, x: float) -> bool:
    """Whether ``x``, once at the field's width, is within the definition's min and max."""
    x = at_width(f, x)
    return (f.minimum is None or x >= f.minimum) and (f.maximum is None or x <= f.maximum)


def next_float(f: FieldDef, x: float, direction: int) -> float:
    """The next representable value of the field's width after ``x`` in ``direction``."""
    fmt, ifmt = ("<f", "<i") if f.size == 4 else ("<d", "<q")
    x = at_width(f, x)
    if x == 0:  # either side of zero: the smallest subnormal, of the direction's sign
        return direction * struct.unpack(fmt, struct.pack(ifmt, 1))[0]
    bits = struct.unpack(ifmt, struct.pack(fmt, x))[0]
    bits += direction if x >= 0 else -direction
    return struct.unpack(fmt, struct.pack(ifmt, bits))[0]


def bound_inside(f: FieldDef, bound: float, direction: int) -> float:
    """The value of the field's width nearest a range bound on the range's side (``direction`` +1 for a minimum,
    -1 for a maximum): an fp32 field cannot hold every fp64 bound (π rounds past it)."""
    x = at_width(f, bound)
    return x if (x - bound) * direction >= 0 else next_float(f, x, direction)


def filled_inline(defs: Definitions, mdef: MessageDef, depth: int) -> dict:
    return inline(mdef.abbrev, {f.abbrev: filled_value(defs, f, depth) for f in mdef.fields})


def filled_fields(defs: Definitions, mdef: MessageDef, depth: int = 1) -> dict:
    return {f.abbrev: filled_value(defs, f, depth) for f in mdef.fields}


def leaf_message(defs: Definitions) -> MessageDef:
    """The first suite message whose fields are all scalars (a compact inline payload)."""
    return next(m for m in defs.suite_messages if m.fields and all(f.is_scalar for f in m.fields))


def inner_types(defs: Definitions, f: FieldDef) -> list[MessageDef]:
    """Message types an inline field or list may hold: its declared types, else the leaf message."""
    if f.message_types:
        return [defs[t] for t in f.message_types]
    return [leaf_message(defs)]


def has_nesting(mdef: MessageDef) -> bool:
    return any(f.type in ("message", "message-list") for f in mdef.fields)


def nested_inline(defs: Definitions, f: FieldDef) -> dict | None:
    """An inline value two levels deep (an inner message that itself holds a message), if one exists."""
    candidates = list(f.message_types and [defs[t] for t in f.message_types] or defs.suite_messages)
    outer = next((m for m in candidates if has_nesting(m)), None)
    if outer is None:
        return None
    return filled_inline(defs, outer, depth=2)


def wrong_type(defs: Definitions, f: FieldDef) -> MessageDef | None:
    """A defined message of scalar fields that is not among the field's declared types (None: there is none)."""
    return next((m for m in defs.suite_messages
                 if m.abbrev not in f.message_types and m.fields and all(x.is_scalar for x in m.fields)), None)


def with_field(base: dict, name: str, value) -> dict:
    out = copy.deepcopy(base)
    out["fields"][name] = value
    return out
