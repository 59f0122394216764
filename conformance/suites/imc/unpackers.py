"""Precompiled unpackers: the fields of a payload the reference codec has checked the frame of, read with one
``struct`` call per run of scalar fields (a plan per message and byte order, built once). They give exactly
what the codec's field-by-field reader gives; anything irregular (a field past the payload's end, an unknown
or too deeply nested inline message) makes them step aside (``Irregular``) so that the reader names it."""

from __future__ import annotations

import struct
from math import inf

from ...kinds.vector.floats import float_from_bits, shortest_float
from ...limits import NESTING_LIMIT
from .definitions import SCALAR_FORMATS, Definitions, MessageDef
from .values import text_value

BITS = {4: "I", 8: "Q"}


class Irregular(Exception):
    """The payload is not one the plan reads straight through: the codec's reader must judge it."""


class _Run:
    """Consecutive scalar fields: one struct, their names, and which of them are floats (index, width)."""

    __slots__ = ("unpack", "size", "names", "floats", "offsets", "bits")

    def __init__(self, e: str, fields: list):
        fmt = e + "".join(SCALAR_FORMATS[f.type] for f in fields)
        s = struct.Struct(fmt)
        self.unpack, self.size, self.names = s.unpack_from, s.size, tuple(f.abbrev for f in fields)
        offsets, pos = [], 0
        for f in fields:
            offsets.append(pos)
            pos += f.size
        self.floats = tuple((i, f.size) for i, f in enumerate(fields) if f.is_float)
        self.offsets = tuple(offsets)
        self.bits = {4: struct.Struct(e + "I").unpack_from, 8: struct.Struct(e + "Q").unpack_from}


def unpackers_of(defs: Definitions) -> Unpackers:
    """The unpackers of ``defs``, made at first use and kept with them (as a cached property would be)."""
    made = defs.__dict__.get("_unpackers")
    if made is None:
        made = defs.__dict__["_unpackers"] = Unpackers(defs)
    return made


class Unpackers:
    """The plans of one set of definitions, built as messages are first read."""

    def __init__(self, defs: Definitions):
        self.defs = defs
        self.plans: dict[tuple[int, str], tuple] = {}
        self.u16 = {e: struct.Struct(e + "H").unpack_from for e in "<>"}

    def plan(self, mdef: MessageDef, e: str) -> tuple:
        key = (mdef.id, e)
        plan = self.plans.get(key)
        if plan is None:
            steps, run = [], []
            for f in mdef.fields:
                if f.is_scalar:
                    run.append(f)
                    continue
                if run:
                    steps.append(_Run(e, run))
                    run = []
                steps.append((f.abbrev, f.type))
            if run:
                steps.append(_Run(e, run))
            plan = self.plans[key] = tuple(steps)
        return plan

    def fields(self, mdef: MessageDef, frame: bytes, e: str, pos: int, end: int, depth: int = 0) -> tuple[dict, int]:
        """(fields, the position after them) of ``mdef`` at ``pos``; raises Irregular."""
        out = {}
        u16 = self.u16[e]
        for step in self.plan(mdef, e):
            if step.__class__ is _Run:
                if pos + step.size > end:
                    raise Irregular
                values = step.unpack(frame, pos)
                if step.floats:
                    values = list(values)
                    for i, width in step.floats:
                        x = values[i]
                        if x != x or x == inf or x == -inf:  # NaN (its bits kept) and the infinities by name
                            values[i] = float_from_bits(step.bits[width](frame, pos + step.offsets[i])[0], width)
                        elif width == 4:
                            values[i] = shortest_float(x, 4)
                out.update(zip(step.names, values))
                pos += step.size
                continue
            name, kind = step
            if pos + 2 > end:
                raise Irregular
            (n,) = u16(frame, pos)
            pos += 2
            if kind == "plaintext" or kind == "rawdata":
                if pos + n > end:
                    raise Irregular
                data = frame[pos:pos + n]
                out[name] = text_value(data) if kind == "plaintext" else data.hex()
                pos += n
            elif kind == "message":
                out[name], pos = self._inline(n, frame, e, pos, end, depth)
            else:
                items = []
                for _ in range(n):
                    if pos + 2 > end:
                        raise Irregular
                    item, pos = self._inline(u16(frame, pos)[0], frame, e, pos + 2, end, depth)
                    items.append(item)
                out[name] = items
        return out, pos

    def _inline(self, mgid: int, frame: bytes, e: str, pos: int, end: int, depth: int):
        if mgid == self.defs.null_id:
            return None, pos
        inner = self.defs.by_id.get(mgid)
        if inner is None or depth >= NESTING_LIMIT:
            raise Irregular
        fields, pos = self.fields(inner, frame, e, pos, end, depth + 1)
        return {"abbrev": inner.abbrev, "fields": fields}, pos
