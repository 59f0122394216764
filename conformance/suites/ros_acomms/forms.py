"""The ROS decoded form: is a value well formed, and how does an answer differ from the expected message.

Vectors must hold exactly the fields of their type in the edition, each value of its field's kind and
range. An answer is malformed (the adapter's fault) only when it is not a ``{"type", "fields"}`` object
of a known type, or a field the definition has holds a value of the wrong kind (``"banana"`` for a
float32); a field the definition lacks, or one missing, is a *difference*: an implementation whose own
definition differs (ROS 1 field names come from each side's .msg files) fails, it is not excused.
"""

from __future__ import annotations

from ...kinds.vector.errors import Difference
from ...kinds.vector.floats import float_to_bits, same_float
from .codec import EXACT_JSON, TIME, int_bounds, int_value, string_bytes
from .definitions import PRIMITIVES, Edition, FieldType, Message


class _Bad(Exception):
    def __init__(self, path: str, what: str):
        super().__init__(what)
        self.path, self.what = path, what


def message_problem(edition: Edition, message, *, strict: bool, in_range: bool = True,
                    expect_type: str | None = None) -> tuple[str, str] | None:
    """``(JSON path suffix, what is wrong)`` for the first problem of a message, or None.

    ``strict`` (a vector): exactly the type's fields, in canonical forms, every value in its field's range
    unless ``in_range`` is false (an encoder's input that must be refused). Otherwise (an answer): only the
    forms of the fields the definition has. ``expect_type``: the type that was asked for.
    """
    try:
        if not isinstance(message, dict) or set(message) != {"type", "fields"}:
            raise _Bad("", f"expected {{type, fields}}, got {_show(message)}")
        full = message["type"]
        if not isinstance(full, str) or full not in edition or edition[full].definition.auxiliary:
            raise _Bad(".type", f"{_show(full)} is not a type of the suite")
        if expect_type is not None and full != expect_type:
            raise _Bad(".type", f"asked for {expect_type}, answered {full}")
        _Walk(edition, strict, strict and in_range).fields(edition[full], message["fields"], ".fields")
    except _Bad as bad:
        return bad.path, bad.what
    return None


class _Walk:
    def __init__(self, edition: Edition, strict: bool, in_range: bool):
        self.edition, self.strict, self.in_range = edition, strict, in_range

    def fields(self, message: Message, fields, path: str) -> None:
        if not isinstance(fields, dict):
            raise _Bad(path, f"expected an object of {message.full} fields, got {_show(fields)}")
        if self.strict:
            extra = sorted(set(fields) - {f.name for f in message.fields})
            if extra:
                raise _Bad(path, f"{extra[0]!r} is not a field of {message.full}")
            missing = [f.name for f in message.fields if f.name not in fields]
            if missing:
                raise _Bad(path, f"{message.full}.{missing[0]} is missing")
        for f in message.fields:
            if f.name in fields:
                self.value(f.type, fields[f.name], f"{path}.{f.name}")

    def value(self, ftype: FieldType, value, path: str) -> None:
        if ftype.array is not None:
            if ftype.base == "uint8":
                if not isinstance(value, str):
                    raise _Bad(path, f"{_show(value)} is not hex ({ftype.text('')})")
                try:
                    data = bytes.fromhex(value)
                except ValueError:
                    raise _Bad(path, f"{_show(value)} is not hex ({ftype.text('')})") from None
                if self.in_range and ftype.array >= 0 and len(data) != ftype.array:
                    raise _Bad(path, f"{len(data)} bytes for {ftype.text('')}")
                return
            if not isinstance(value, list):
                raise _Bad(path, f"expected an array ({ftype.text('')}), got {_show(value)}")
            if self.in_range and ftype.array >= 0 and len(value) != ftype.array:
                raise _Bad(path, f"{len(value)} elements for {ftype.text('')}")
            for i, element in enumerate(value):
                self.value(ftype.element, element, f"{path}[{i}]")
            return
        base = ftype.base
        if base == "bool":
            if not isinstance(value, bool):
                raise _Bad(path, f"{_show(value)} is not a boolean")
        elif base in ("float32", "float64"):
            if self.strict or not (type(value) in (int, float)):
                try:
                    float_to_bits(value, PRIMITIVES[base][1])
                except ValueError as exc:
                    raise _Bad(path, f"{_show(value)} is not a {base} value: {exc}") from None
        elif base in PRIMITIVES:
            number = int_value(value)
            if number is None:
                raise _Bad(path, f"{_show(value)} is not an integer ({base})")
            if self.strict and (type(value) is int) != (abs(number) < EXACT_JSON):
                raise _Bad(path, f"{_show(value)}: an integer is written as a JSON number below 2**53, else as a string")
            lo, hi = int_bounds(base)
            if self.in_range and not lo <= number <= hi:
                raise _Bad(path, f"{number} does not fit {base} [{lo}, {hi}]")
        elif base == "string":
            try:
                string_bytes(value)
            except ValueError:
                raise _Bad(path, f"{_show(value)} is not a string value") from None
        elif base in TIME:
            if not isinstance(value, dict) or set(value) != {"secs", "nsecs"} or \
                    not all(type(v) is int for v in value.values()):
                raise _Bad(path, f"{_show(value)} is not {{secs, nsecs}} ({base})")
            if self.in_range:
                fmt = "I" if base == "time" else "i"
                lo, hi = int_bounds("uint32" if fmt == "I" else "int32")
                if not all(lo <= v <= hi for v in value.values()):
                    raise _Bad(path, f"{value} does not fit {base}")
        else:
            self.fields(self.edition[base], value, path)


# ---------------------------------------------------------------- comparison

def differences(edition: Edition, expected: dict, actual, nan_payload: bool = False) -> list[Difference]:
    if not isinstance(actual, dict) or not isinstance(actual.get("fields"), dict):
        return [Difference("message", expected["type"], actual, "not a {type, fields} object")]
    if actual.get("type") != expected["type"]:
        return [Difference("type", expected["type"], actual.get("type"))]
    out: list[Difference] = []
    message = edition[expected["type"]]
    _compare_fields(edition, message, expected["fields"], actual["fields"], message.name, nan_payload, out)
    return out


def _compare_fields(edition, message: Message, expected: dict, actual, path: str, nan_payload: bool, out: list) -> None:
    if not isinstance(actual, dict):
        out.append(Difference(path, "an object", actual))
        return
    for f in message.fields:
        if f.name not in actual:
            out.append(Difference(f"{path}.{f.name}", expected[f.name], None, "missing"))
        else:
            _compare(edition, f.type, expected[f.name], actual[f.name], f"{path}.{f.name}", nan_payload, out)
    for extra in sorted(set(actual) - {f.name for f in message.fields}):
        out.append(Difference(f"{path}.{extra}", None, actual[extra], f"not a field of {message.full}"))


def _compare(edition, ftype: FieldType, e, a, path: str, nan_payload: bool, out: list) -> None:
    base = ftype.base
    if ftype.array is not None and base == "uint8":
        try:
            same = bytes.fromhex(e) == bytes.fromhex(a)
        except (TypeError, ValueError):
            same = False
        if not same:
            out.append(Difference(path, e, a, ftype.text("")))
    elif ftype.array is not None:
        if not isinstance(a, list) or len(a) != len(e):
            out.append(Difference(path, f"{len(e)} elements", f"{len(a)} elements" if isinstance(a, list) else a))
            return
        for i, (x, y) in enumerate(zip(e, a)):
            _compare(edition, ftype.element, x, y, f"{path}[{i}]", nan_payload, out)
    elif base == "bool":
        if a is not e:
            out.append(Difference(path, e, a, "bool"))
    elif base in ("float32", "float64"):
        if not same_float(e, a, PRIMITIVES[base][1], nan_payload):
            out.append(Difference(path, e, a, base))
    elif base in PRIMITIVES:
        if int_value(a) != int_value(e) or isinstance(a, bool):
            out.append(Difference(path, e, a, base))
    elif base == "string":
        try:
            same = string_bytes(e) == string_bytes(a)
        except ValueError:
            same = False
        if not same:
            out.append(Difference(path, e, a, "string"))
    elif base in TIME:
        if a != e:
            out.append(Difference(path, e, a, base))
    else:
        _compare_fields(edition, edition[base], e, a, path, nan_payload, out)


def _show(value) -> str:
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."
