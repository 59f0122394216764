"""Generic message values built from the definitions alone: defaults, filled values, nesting."""

from __future__ import annotations

import copy

from ..definitions import Definitions, FieldDef, MessageDef

# Distinctive, in-range values by integer type (bytes that are easy to spot in a hex dump).
FILLED_INTS = {"uint8_t": 42, "int8_t": -5, "uint16_t": 4660, "int16_t": -1234, "uint32_t": 305419896,
               "int32_t": -123456, "int64_t": -1234567890123}


def default_value(f: FieldDef):
    """The zero of the field's type; for an enum whose table lacks 0, its lowest value in every edition."""
    if f.enum_kind == "enum" and not any(v.value == 0 for v in f.enum_values):
        return min(v.value for v in f.enum_values if v.editions is None)
    if f.is_float:
        return 0.0
    if f.is_int:
        return 0
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
        return FILLED_INTS[f.type]
    if f.is_float:
        if f.minimum is not None or f.maximum is not None:
            return 0.5
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
