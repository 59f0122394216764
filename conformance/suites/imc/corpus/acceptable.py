"""Acceptable vectors: implementation-defined behaviour, recorded rather than failed.

Each record names its class of rules.json (``classes``: where the freedom comes from, quoted), lists the outcomes
the class permits (``accept`` with the given message or frames, ``reject``, ``lossy`` text, a ``restamp``ed zero
timestamp, or for an out-of-type enum value ``truncate`` / ``saturate`` with their frames) and the ``reference``
outcome that DUNE and imcpy show (imc-wire.md, "What real receivers do").
"""

from __future__ import annotations

import functools
import json

from .. import codec
from ..definitions import FieldDef
from . import samples
from .records import MessageCases
from .surgery import payload_of, reframe
from .valid import first_variable_field, max_fill
from ..paths import imc_data
from ....kinds.vector.floats import F32_MAX

RECEIVERS = "imc-wire#what-real-receivers-do"
DECODE_BOTH = ["decode-le", "decode-be"]
CODEC_BOTH = ["encode-le", "encode-be", "decode-le", "decode-be"]


@functools.cache
def classes() -> dict[str, dict]:
    """The implementation-defined classes of rules.json, by id."""
    return {c["id"]: c for c in json.loads(imc_data("rules.json").read_text(encoding="utf-8"))["classes"]}


def outcomes(klass: str, **frames) -> list[dict]:
    """The outcomes a class permits, in its order; ``frames``: the frames of the outcomes that write their own."""
    named = classes()[klass].get("refusals")
    return [{"outcome": o, **({"frames": {e: f.hex() for e, f in frames[o].items()}} if o in frames else {}),
             **({"rules": named} if o == "reject" and named else {})} for o in classes()[klass]["outcomes"]]


def add_acceptable(mc: MessageCases) -> None:
    defs, mdef = mc.defs, mc.mdef
    filled = samples.message(mdef.abbrev, samples.filled_fields(defs, mdef), samples.ORDINARY_HEADER)
    canonical, frames = mc.both_orders(filled)

    def acceptable(path, klass, *, frames, message, checks, clause, tags, **extra):
        extra.setdefault("outcomes", outcomes(klass))
        return mc.add(path, expect="acceptable", clause=clause, checks=checks, tags=["acceptable", *tags],
                      frames=frames, message=message, reference=classes()[klass]["reference"], **{"class": klass},
                      **extra)

    acceptable("trailing-bytes", "trailing-bytes", frames={o: f + b"\x00\x11\x22" for o, f in frames.items()},
               message=canonical, checks=DECODE_BOTH, clause=RECEIVERS, tags=["framing", "trailing-bytes"],
               comment="Three bytes follow the footer; DUNE and imcpy ignore them.")
    acceptable("unused-payload", "unused-payload", frames={o: with_unused_payload(f, o, 2) for o, f in frames.items()},
               message=canonical, checks=DECODE_BOTH, clause=RECEIVERS, tags=["framing", "unused-payload"],
               comment="The size field covers two bytes after the last field; they are CRC-covered and ignored.")
    for f in mdef.fields:
        for path, value, clause, tags, extra in field_cases(mc, f):
            message = samples.with_field(filled, f.abbrev, value)
            klass = extra.pop("class")
            if extra.pop("decode_only", False):
                msg_frames = {o: codec.encode(defs, message, o) for o in ("le", "be")}
                acceptable(path, klass, frames=msg_frames, message=codec.decode(defs, msg_frames["le"]), checks=DECODE_BOTH,
                           clause=clause, tags=[*tags, f"field:{f.abbrev}"], **extra)
                continue
            msg_canonical, msg_frames = mc.both_orders(message)
            acceptable(path, klass, frames=msg_frames, message=msg_canonical, checks=CODEC_BOTH, clause=clause,
                       tags=[*tags, f"field:{f.abbrev}"], **extra)
        for v in f.enum_values:
            if f.is_int and not f.int_bounds[0] <= v.value <= f.int_bounds[1]:
                add_out_of_type(mc, filled, f, v)
    for order in ("le", "be"):
        add_oversize(mc, acceptable, order)


def field_cases(mc: MessageCases, f: FieldDef):
    """(path, value, clause, tags, extra) of each acceptable variant of one field."""
    defs = mc.defs
    if f.enum_kind == "enum":
        known = {v.value for v in f.enum_values}
        lo, hi = f.int_bounds
        first_free = next((x for x in range(lo, hi + 1) if x not in known), hi)  # a full table has none
        for value in sorted({first_free, hi} - known):
            yield (f"enum-out-of-table/{f.abbrev}/{value}", value, RECEIVERS, ["enum", "out-of-table"],
                   {"class": "enum-out-of-table", "comment": f"{value} is in no edition's table; DUNE and imcpy carry it unchanged."})
    elif f.enum_kind == "bitfield":
        defined = 0
        for v in f.enum_values:
            defined |= v.value
        undefined = [1 << b for b in range(8 * f.size) if not defined & (1 << b)]
        for bit in sorted({undefined[0], undefined[-1]}) if undefined else ():  # a table of every bit has none
            yield (f"bitfield-undefined/{f.abbrev}/0x{bit:x}", bit, RECEIVERS, ["bitfield", "undefined-bit"],
                   {"class": "bitfield-undefined", "comment": "A bit the table does not define; DUNE and imcpy carry it unchanged."})
    elif f.is_int and (f.minimum is not None or f.maximum is not None):
        lo, hi = f.int_bounds
        rlo, rhi = f.int_range
        seen = set()
        for name, value in (("below-min", rlo - 1), ("type-min", lo), ("above-max", rhi + 1), ("type-max", hi)):
            if value in seen or not lo <= value <= hi or rlo <= value <= rhi:
                continue
            seen.add(value)
            yield (f"out-of-range/{f.abbrev}/{name}", value, f.range_source, ["out-of-range", f"class:{name}"],
                   {"class": "out-of-range", "comment": "Outside the field's declared min/max; validation is optional, DUNE and imcpy carry it."})
    elif f.is_float and (f.minimum is not None or f.maximum is not None):
        outside = {"nan": "nan", "inf": "inf", "negative-inf": "-inf"}
        if f.minimum is not None:
            outside["below-min"] = samples.next_float(f, f.minimum, -1)
        if f.maximum is not None:
            outside["above-max"] = samples.next_float(f, f.maximum, +1)
            outside["max-finite"] = F32_MAX if f.size == 4 else 1.7976931348623157e308
        for name, value in outside.items():
            yield (f"out-of-range/{f.abbrev}/{name}", value, f.range_source, ["out-of-range", f"class:{name}"],
                   {"class": "out-of-range", "comment": "Outside the field's declared min/max; validation is optional, DUNE and imcpy carry it."})
    elif f.type == "plaintext":
        for name, raw in (("utf8", "ol\u00e1 \u00e9\u00e8".encode()), ("invalid-utf8", b"\xff\xfe\xc3"), ("latin1", b"caf\xe9")):
            yield (f"text/{f.abbrev}/{name}", {"hex": raw.hex()}, "imc-wire#field-types", ["text", "non-ascii", f"class:{name}"],
                   {"class": "non-ascii-text", "comment": "Plaintext is specified as ASCII; DUNE copies the raw bytes, imcpy's "
                                                          "getters replace them (lossy); a receiver may also refuse them."})
    elif f.type in ("message", "message-list") and f.message_types and samples.wrong_type(defs, f):
        other = samples.wrong_type(defs, f)
        value = samples.filled_inline(defs, other, 0)
        yield (f"wrong-inline-type/{f.abbrev}/{other.abbrev}", value if f.type == "message" else [value],
               f.clause, ["inline", "wrong-type"],
               {"decode_only": True, "class": "wrong-inline-type",
                "comment": f"{other.abbrev} where the definition names {', '.join(f.message_types)}; DUNE accepts any defined message."})
    if f.type == "message-list":
        element = samples.filled_inline(defs, samples.inner_types(defs, f)[0], 0)
        yield (f"null-list-element/{f.abbrev}", [element, None], "imc-wire#field-types", ["list", "null-element"],
               {"class": "null-list-element", "comment": "An element id FF FF is a null element: DUNE keeps it as a null "
                                                         "entry and writes it; a receiver may refuse it, an encoder too."})


def add_out_of_type(mc: MessageCases, filled: dict, f: FieldDef, v) -> None:
    """An enum value that cannot fit its field (the seeds' UNSUPPORTED = 666 in a uint8): how does an encoder react?"""
    lo, hi = f.int_bounds
    truncated = v.value & hi if lo == 0 else v.value
    alternatives = {"truncate": truncated, "saturate": hi if v.value > hi else lo}
    frames = {name: mc.both_orders(samples.with_field(filled, f.abbrev, value))[1] for name, value in alternatives.items()}
    editions = v.editions or mc.defs.editions
    mc.add(f"enum-out-of-type/{f.abbrev}/{v.abbrev}-{v.value}", expect={e: "acceptable" for e in editions},
           clause=v.source, checks=["encode-le", "encode-be"], tags=["acceptable", "enum", "out-of-type", f"field:{f.abbrev}", "edition-specific"],
           message=samples.with_field(filled, f.abbrev, v.value), outcomes=outcomes("enum-out-of-type", **frames),
           reference=classes()["enum-out-of-type"]["reference"], erratum=erratum_of(v), **{"class": "enum-out-of-type"},
           comment=(f"{v.abbrev} = {v.value} cannot be carried in {f.type}: imcpy refuses it, older DUNE builds "
                    f"put {truncated} on the wire (truncation)."))
    message = samples.with_field(filled, f.abbrev, truncated)
    canonical, frames = mc.both_orders(message)
    mc.add(f"enum-out-of-type/{f.abbrev}/{v.abbrev}-{v.value}-as-sent-by-old-dune", expect="acceptable", clause=v.source,
           checks=DECODE_BOTH, tags=["acceptable", "enum", "out-of-table", f"field:{f.abbrev}"], frames=frames,
           message=canonical, outcomes=outcomes("enum-out-of-table"), reference=classes()["enum-out-of-table"]["reference"],
           erratum=erratum_of(v), **{"class": "enum-out-of-table"},
           comment=f"The byte old DUNE builds emitted for {v.abbrev}: out of every table, carried unchanged by DUNE and imcpy.")


def erratum_of(v) -> str | None:
    return v.source.split("#", 1)[1] if v.source.startswith("imc-wire#E") else None


def with_unused_payload(frame: bytes, order: str, extra: int) -> bytes:
    """The frame with ``extra`` zero bytes appended to its payload, size and CRC updated."""
    return reframe(frame, order, payload=payload_of(frame, order) + bytes(extra))


def add_oversize(mc: MessageCases, acceptable, order: str) -> None:
    """A real frame one byte over DUNE's cap (65,536 bytes, a payload of 65,514): a rule of practice, so a receiver
    may decode it and an encoder may write it; held to DUNE's practice, both must refuse it."""
    f = first_variable_field(mc)
    if f is None:
        return
    fill = max_fill(mc, f, extra=1)
    value = "x" * fill if f.type == "plaintext" else "a5" * fill
    base = samples.message(mc.mdef.abbrev, samples.default_fields(mc.mdef), samples.ORDINARY_HEADER)
    message = samples.with_field(base, f.abbrev, value)
    frame = codec.encode(mc.defs, message, order)
    acceptable(f"size-limit/actual-65514-{f.abbrev}/{order}", "size-limit", frames={order: frame},
               message=codec.decode(mc.defs, frame), checks=[f"encode-{order}", f"decode-{order}"], clause=RULE_CLAUSE,
               tags=["size-limit", "practice", f"byte-order:{order}", f"field:{f.abbrev}"], practice="size-limit",
               comment="A 65,536-byte frame (a payload of 65,514): over DUNE's cap, within what IMC's u16 size carries.")


RULE_CLAUSE = "imc-wire#frame-layout"
