"""Valid vectors: minimal, realistic, header variants, enum values, bitfield bits, numeric boundaries,
text and raw extremes, inline and list shapes. Every one is checked in both byte orders."""

from __future__ import annotations

from ....kinds.vector.floats import FLOAT_CLASSES, NON_FINITE, PAYLOAD_NANS
from .. import codec
from ..definitions import FieldDef
from . import samples
from .records import ALL_CHECKS, MessageCases

HEADER_VARIANTS = {
    "zero": {"timestamp": 0.0, "src": 0, "src_ent": 0, "dst": 0, "dst_ent": 0},
    "non-default": {"timestamp": 1700000000.5, "src": 0x4101, "src_ent": 7, "dst": 0x001E, "dst_ent": 43},
    "max-addresses": {"timestamp": 1.0, "src": 0xFFFE, "src_ent": 0xFE, "dst": 0xFFFE, "dst_ent": 0xFE},
    "fractional-timestamp": {"timestamp": 1700000000.123456},
    "negative-zero-timestamp": {"timestamp": -0.0},
    "far-future-timestamp": {"timestamp": 4102444800.0},
    "system-entity": {"src": 0x001E, "src_ent": 0, "dst": 0x4101, "dst_ent": 0},
}
# Zero timestamps: decoding them has no freedom; an encoder may write them or stamp the time of sending (class
# zero-timestamp), so their encode and roundtrip checks are acceptable cases of their own.
ZERO_TIMESTAMPS = ("zero", "negative-zero-timestamp")
BASE = "filled"  # the valid case (path) every invalid case of a message is made from
DECODE_CHECKS = ["decode-le", "decode-be"]
PRINTABLE = "".join(chr(c) for c in range(0x20, 0x7F))
CONTROL = "".join(chr(c) for c in (0x00, 0x09, 0x0A, 0x0D, 0x1B, 0x7F))


def float_in_range(f: FieldDef, value) -> bool:
    if isinstance(value, str):
        return f.minimum is None and f.maximum is None
    return samples.in_float_range(f, value)


def add_valid(mc: MessageCases, examples: list[dict]) -> None:
    defs, mdef = mc.defs, mc.mdef
    minimal = samples.message(mdef.abbrev, samples.default_fields(mdef))

    def valid(path: str, message: dict, clause: str, tags: list[str], expect="valid", checks=ALL_CHECKS, **extra):
        if isinstance(expect, dict) and "acceptable" in expect.values():
            # valid in one edition, out of the table (implementation-defined) in another
            extra.update(outcomes=[{"outcome": "accept"}, {"outcome": "reject"}], reference="accept",
                         **{"class": "out-of-range" if "out-of-range" in tags else "enum-out-of-table"})
        canonical, frames = mc.both_orders(message)
        return mc.add(path, expect=expect, clause=clause, checks=checks, tags=["valid", *tags],
                      frames=frames, message=canonical, **extra)

    valid("minimal", minimal, mdef.clause, ["minimal", "defaults"])
    for example in examples:
        canonical, _ = mc.both_orders(example["message"])
        if canonical != example["message"]:
            raise ValueError(f"example {mdef.abbrev}/{example['name']} is not in canonical form: {canonical}")
        valid(f"realistic/{example['name']}", example["message"], example["source"], ["realistic"])
    for name, header in HEADER_VARIANTS.items():
        if name not in ZERO_TIMESTAMPS:
            valid(f"header/{name}", dict(minimal, header=header), "imc-wire#frame-layout", ["header"])
            continue
        valid(f"header/{name}/decode", dict(minimal, header=header), "imc-wire#frame-layout", ["header"],
              checks=DECODE_CHECKS)
        canonical, frames = mc.both_orders(dict(minimal, header=header))
        mc.add(f"header/{name}/encode", expect="acceptable", clause="imc-xml#header.timestamp",
               checks=["encode-le", "encode-be", "roundtrip"], tags=["acceptable", "header", "zero-timestamp"],
               frames=frames, message=canonical, outcomes=[{"outcome": "accept"}, {"outcome": "restamp"}],
               reference="accept", **{"class": "zero-timestamp"},
               comment="A zero timestamp given to an encoder: written as given (DUNE, imcpy), or the time of sending.")
    # every field filled, an ordinary header: the frame the invalid cases are made from (their ``base``)
    valid(BASE, samples.message(mdef.abbrev, samples.filled_fields(defs, mdef), samples.ORDINARY_HEADER), mdef.clause,
          ["filled"])
    for f in mdef.fields:
        for path, value, clause, tags, expect in field_variants(mc, f):
            valid(f"{path}", samples.with_field(minimal, f.abbrev, value), clause, [*tags, f"field:{f.abbrev}"],
                  expect=expect, **({"compare": {"nan_payload": True}} if PAYLOAD_NANS & set(tags) else {}))


def field_variants(mc: MessageCases, f: FieldDef):
    """(path, value, clause, tags, expect) for each valid variant of one field."""
    defs = mc.defs
    if f.enum_kind == "enum":
        lo, hi = f.int_bounds
        rlo, rhi = f.int_range
        for v in f.enum_values:
            if not lo <= v.value <= hi:
                continue  # cannot fit the field type: an acceptable encode case (see acceptable.py)
            expect = ("valid" if v.editions is None else
                      {e: ("valid" if e in v.editions else "acceptable") for e in defs.editions})
            tags = ["enum", f"value:{v.abbrev}"] + ([] if v.editions is None else ["edition-specific"])
            if not rlo <= v.value <= rhi:  # the table and the field's min/max disagree: either reading holds
                expect = {e: "acceptable" for e in defs.editions}
                tags.append("out-of-range")
            yield f"enum/{f.abbrev}/{v.abbrev}-{v.value}", v.value, v.source, tags, expect
        return
    if f.enum_kind == "bitfield":
        for v in f.enum_values:
            yield f"bitfield/{f.abbrev}/{v.abbrev}", v.value, v.source, ["bitfield", f"value:{v.abbrev}"], "valid"
        yield f"bitfield/{f.abbrev}/none", 0, f.clause, ["bitfield", "class:zero"], "valid"
        yield f"bitfield/{f.abbrev}/all", samples.filled_value(defs, f), f.clause, ["bitfield", "class:all"], "valid"
        return
    if f.is_int:
        lo, hi = f.int_bounds
        rlo, rhi = f.int_range
        classes = {"min": lo, "max": hi, "zero": 0, "one": 1}
        if lo < 0:
            classes["minus-one"] = -1
        if f.minimum is not None:
            classes["range-min"] = rlo
        if f.maximum is not None:
            classes["range-max"] = rhi
        for name, value in classes.items():
            if rlo <= value <= rhi:
                clause = f.range_source if name.startswith("range-") else f.clause
                yield f"boundary/{f.abbrev}/{name}", value, clause, ["boundary", f"class:{name}"], "valid"
        return
    if f.is_float:
        width = f.size
        classes = {name: vals[0 if width == 4 else 1] for name, vals in FLOAT_CLASSES.items()}
        if f.minimum is not None:
            classes["range-min"] = samples.bound_inside(f, f.minimum, +1)
        if f.maximum is not None:
            classes["range-max"] = samples.bound_inside(f, f.maximum, -1)
        for name, value in classes.items():
            if float_in_range(f, value) and not (name in NON_FINITE and (f.minimum is not None or f.maximum is not None)):
                clause = f.range_source if name.startswith("range-") else f.clause
                yield f"boundary/{f.abbrev}/{name}", value, clause, ["boundary", f"class:{name}"], "valid"
        return
    if f.type == "plaintext":
        yield f"text/{f.abbrev}/empty", "", f.clause, ["text", "class:empty"], "valid"
        yield f"text/{f.abbrev}/printable-ascii", PRINTABLE, f.clause, ["text", "class:printable-ascii"], "valid"
        yield f"text/{f.abbrev}/control-ascii", CONTROL, f.clause, ["text", "class:control-ascii"], "valid"
        yield f"text/{f.abbrev}/long", (PRINTABLE * 11)[:1000], f.clause, ["text", "class:long"], "valid"
        if f is first_variable_field(mc):
            yield f"{variable_kind(f)}/{f.abbrev}/max-payload", "x" * max_fill(mc, f), "imc-wire#frame-layout", ["text", "class:max-payload", "oversize"], "valid"
        return
    if f.type == "rawdata":
        yield f"raw/{f.abbrev}/empty", "", f.clause, ["raw", "class:empty"], "valid"
        yield f"raw/{f.abbrev}/all-bytes", bytes(range(256)).hex(), f.clause, ["raw", "class:all-bytes"], "valid"
        if f is first_variable_field(mc):
            yield f"{variable_kind(f)}/{f.abbrev}/max-payload", "a5" * max_fill(mc, f), "imc-wire#frame-layout", ["raw", "class:max-payload", "oversize"], "valid"
        return
    types = samples.inner_types(defs, f)
    if f.type == "message":
        yield f"inline/{f.abbrev}/null", None, "imc-wire#field-types", ["inline", "class:null"], "valid"
        for inner in types:
            yield (f"inline/{f.abbrev}/{inner.abbrev}", samples.filled_inline(defs, inner, 0),
                   f.clause, ["inline", "class:one"], "valid")
        nested = samples.nested_inline(defs, f)
        if nested is not None:
            yield f"inline/{f.abbrev}/nested", nested, f.clause, ["inline", "class:nested", "nested"], "valid"
        return
    element = samples.filled_inline(defs, types[0], 0)
    yield f"list/{f.abbrev}/empty", [], f.clause, ["list", "class:empty"], "valid"
    yield f"list/{f.abbrev}/one", [element], f.clause, ["list", "class:one"], "valid"
    many = [samples.filled_inline(defs, types[i % len(types)], 0) for i in range(3)]
    yield f"list/{f.abbrev}/many", many, f.clause, ["list", "class:many"], "valid"
    yield f"list/{f.abbrev}/hundred", [element] * 100, f.clause, ["list", "class:long"], "valid"
    nested = samples.nested_inline(defs, f)
    if nested is not None:
        yield f"list/{f.abbrev}/nested", [nested, element], f.clause, ["list", "class:nested", "nested"], "valid"


def first_variable_field(mc: MessageCases) -> FieldDef | None:
    return next((f for f in mc.mdef.fields if f.type in ("plaintext", "rawdata")), None)


def variable_kind(f: FieldDef) -> str:
    """The path segment of a plaintext's (``text``) or rawdata's (``raw``) valid cases."""
    return "text" if f.type == "plaintext" else "raw"


def max_fill(mc: MessageCases, f: FieldDef, extra: int = 0) -> int:
    """Bytes to put in ``f`` (other fields minimal) so the payload is exactly max_payload + extra."""
    minimal = codec.encode_payload(mc.defs, mc.mdef, samples.default_fields(mc.mdef), "<")
    return mc.defs.max_payload + extra - len(minimal)
