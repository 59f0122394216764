"""Is a value a well-formed IMC message in the corpus's decoded form? Driven by the definitions alone.

One grammar serves two readers: the corpus loader (every message of every vector must be well formed,
or the corpus is in error) and the judge (an adapter's answer that is not well formed is the adapter's
fault, never the implementation's). Integers must be JSON integers, floats numbers or one of the float
strings, text and raw bytes one of their forms; inline messages and lists nest the same rules. A vector
must also hold only values its field can carry (an integer that fits the type or is a value of the
field's enumeration, such as the seeds' 666 that no uint8 holds; a float that fits its width), while
an answer may hold any value of the right kind: a wrong value is the implementation's failure.
"""

from __future__ import annotations

from ...limits import NESTING_LIMIT
from .definitions import Definitions, FieldDef, MessageDef
from ...kinds.vector.floats import float_to_bits
from .values import raw_bytes, text_bytes

HEADER_TYPES = {"timestamp": "fp64_t", "src": "uint16_t", "src_ent": "uint8_t", "dst": "uint16_t", "dst_ent": "uint8_t"}
HEADER = MessageDef(id=-1, abbrev="header", name="header", clause="imc-wire#frame-layout", min_payload=0,
                    fields=tuple(FieldDef(abbrev=k, name=k, type=t, clause="imc-wire#frame-layout")
                                 for k, t in HEADER_TYPES.items()))


class _Malformed(Exception):
    def __init__(self, path: str, what: str):
        super().__init__(what)
        self.path, self.what = path, what


def message_problem(defs: Definitions, message, *, whole_header: bool, in_range: bool) -> tuple[str, str] | None:
    """``(JSON path suffix, what is wrong)`` for the first problem of a top-level message, or None.

    ``whole_header``: all five header fields must be present (a decoded form); otherwise any subset may
    be given (an encoder's input, the rest taking their defaults). ``in_range``: every value must be one
    its field can carry (a vector), not merely of the right kind (an answer).
    """
    try:
        _Walk(defs, in_range).top(message, whole_header)
    except _Malformed as bad:
        return bad.path, bad.what
    return None


class _Walk:
    def __init__(self, defs: Definitions, in_range: bool):
        self.defs, self.in_range = defs, in_range
        self.depth = 0

    def top(self, message, whole_header: bool) -> None:
        if not isinstance(message, dict):
            raise _Malformed("", f"expected a message object, got {_show(message)}")
        extra = set(message) - {"abbrev", "header", "fields"}
        if extra:
            raise _Malformed("", f"unexpected key {sorted(extra)[0]!r} (a message has abbrev, header and fields)")
        mdef = self.definition(message.get("abbrev"), ".abbrev")
        header = message.get("header")
        if not isinstance(header, dict):
            raise _Malformed(".header", f"expected an object of header fields, got {_show(header)}")
        self.fields(HEADER, header, ".header", complete=whole_header)
        self.fields(mdef, message.get("fields"), ".fields", complete=True)

    def definition(self, abbrev, path: str) -> MessageDef:
        mdef = self.defs.by_abbrev.get(abbrev) if isinstance(abbrev, str) else None
        if mdef is None:
            raise _Malformed(path, f"{_show(abbrev)} is not a message of the definitions")
        return mdef

    def fields(self, mdef: MessageDef, fields, path: str, complete: bool) -> None:
        if not isinstance(fields, dict):
            raise _Malformed(path, f"expected an object of {mdef.abbrev} fields, got {_show(fields)}")
        extra = sorted(set(fields) - {f.abbrev for f in mdef.fields})
        if extra:
            raise _Malformed(path, f"{extra[0]!r} is not a field of {mdef.abbrev}")
        missing = [f.abbrev for f in mdef.fields if f.abbrev not in fields]
        if complete and missing:
            raise _Malformed(path, f"{mdef.abbrev}.{missing[0]} is missing")
        for f in mdef.fields:
            if f.abbrev in fields:
                self.value(f, fields[f.abbrev], f"{path}.{f.abbrev}")

    def value(self, f: FieldDef, value, path: str) -> None:
        if f.is_int:
            if type(value) is not int:
                raise _Malformed(path, f"{_show(value)} is not an integer ({f.type})")
            lo, hi = f.int_bounds
            if self.in_range and not lo <= value <= hi and value not in {v.value for v in f.enum_values}:
                raise _Malformed(path, f"{value} does not fit {f.type} [{lo}, {hi}]")
            return
        try:
            if f.is_float and (self.in_range or isinstance(value, str) or type(value) not in (int, float)):
                float_to_bits(value, f.size)
            elif f.type == "plaintext":
                text_bytes(value)
            elif f.type == "rawdata":
                raw_bytes(value)
        except (ValueError, TypeError) as exc:
            raise _Malformed(path, f"{_show(value)} is not a {f.type} value: {exc}") from None
        if f.type == "message":
            self.inline(value, path)
        elif f.type == "message-list":
            if not isinstance(value, list):
                raise _Malformed(path, f"expected an array (message-list), got {_show(value)}")
            for i, element in enumerate(value):
                self.inline(element, f"{path}[{i}]")

    def inline(self, value, path: str) -> None:
        if value is None:
            return
        if not isinstance(value, dict) or set(value) != {"abbrev", "fields"}:
            raise _Malformed(path, f"expected null or an inline message {{abbrev, fields}}, got {_show(value)}")
        if self.depth >= NESTING_LIMIT:
            raise _Malformed(path, f"inline messages nested deeper than {NESTING_LIMIT} levels")
        self.depth += 1
        self.fields(self.definition(value["abbrev"], f"{path}.abbrev"), value["fields"], f"{path}.fields", complete=True)
        self.depth -= 1


def used_abbrevs(defs: Definitions, message: dict, found: set[str]) -> set[str]:
    """``found`` with the abbreviation of a well-formed decoded message and of every inline message in it, read by
    the definitions (a field named ``abbrev`` or ``fields`` is a field) and iteratively (no recursion an input
    could drive)."""
    stack = [message]
    while stack:
        m = stack.pop()
        found.add(m["abbrev"])
        for f in defs[m["abbrev"]].fields:
            if f.type in ("message", "message-list"):
                value = m["fields"][f.abbrev]
                stack += [x for x in (value if isinstance(value, list) else [value]) if x is not None]
    return found


def _show(value) -> str:
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."
