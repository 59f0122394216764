"""Compare an implementation's decoded message with the expected one, as the corpus's policy says.

Values are compared at the field's width (a fp32 answered as the double 0.10000000149011612 equals
the expected 0.1); ``-0.0`` differs from ``0.0``; any NaN matches ``"nan"`` unless the case asks for
exact NaN payloads; plaintext compares as bytes (a string stands for its UTF-8 encoding).
"""

from __future__ import annotations

from dataclasses import dataclass

from .definitions import Definitions, FieldDef, MessageDef
from .values import float_to_bits, raw_bytes, text_bytes

HEADER_TYPES = {"timestamp": "fp64_t", "src": "uint16_t", "src_ent": "uint8_t", "dst": "uint16_t", "dst_ent": "uint8_t"}


@dataclass(frozen=True)
class Difference:
    path: str
    expected: object
    actual: object
    why: str = ""

    def __str__(self) -> str:
        why = f" ({self.why})" if self.why else ""
        return f"{self.path}: expected {self.expected!r}, got {self.actual!r}{why}"


_MISSING = object()


class Comparator:
    """Compares decoded messages against one set of definitions."""

    def __init__(self, defs: Definitions):
        self.defs = defs
        self._header = {k: FieldDef(abbrev=k, name=k, type=t, clause="imc-wire#frame-layout") for k, t in HEADER_TYPES.items()}

    def messages(self, expected: dict, actual, *, nan_payload: bool = False) -> list[Difference]:
        out: list[Difference] = []
        if not isinstance(actual, dict):
            return [Difference("message", expected.get("abbrev"), actual, "not an object")]
        if actual.get("abbrev") != expected["abbrev"]:
            return [Difference("abbrev", expected["abbrev"], actual.get("abbrev"))]
        header = actual.get("header")
        if not isinstance(header, dict):
            out.append(Difference("header", expected.get("header"), header, "not an object"))
        else:
            for name, f in self._header.items():
                self._value(f, expected["header"][name], header.get(name, _MISSING), f"header.{name}", nan_payload, out)
        self._fields(self.defs[expected["abbrev"]], expected["fields"], actual.get("fields"), expected["abbrev"], nan_payload, out)
        return out

    def _fields(self, mdef: MessageDef, expected: dict, actual, path: str, nan_payload: bool, out: list) -> None:
        if not isinstance(actual, dict):
            out.append(Difference(f"{path}.fields", "an object", actual))
            return
        for f in mdef.fields:
            self._value(f, expected[f.abbrev], actual.get(f.abbrev, _MISSING), f"{path}.{f.abbrev}", nan_payload, out)
        for extra in sorted(set(actual) - {f.abbrev for f in mdef.fields}):
            out.append(Difference(f"{path}.{extra}", _MISSING, actual[extra], "not a field of " + mdef.abbrev))

    def _value(self, f: FieldDef, expected, actual, path: str, nan_payload: bool, out: list) -> None:
        if actual is _MISSING:
            out.append(Difference(path, expected, None, "missing"))
        elif f.is_float:
            if not _same_float(expected, actual, f.size, nan_payload):
                out.append(Difference(path, expected, actual, f"{f.type}"))
        elif f.is_int:
            if isinstance(actual, bool) or actual != expected or not isinstance(actual, int):
                out.append(Difference(path, expected, actual, f.type))
        elif f.type in ("plaintext", "rawdata"):
            convert = text_bytes if f.type == "plaintext" else raw_bytes
            try:
                same = convert(expected) == convert(actual)
            except (ValueError, TypeError):
                same = False
            if not same:
                out.append(Difference(path, expected, actual, f.type))
        elif f.type == "message":
            self._inline(expected, actual, path, nan_payload, out)
        elif not isinstance(actual, list) or len(actual) != len(expected):
            out.append(Difference(path, f"{len(expected)} elements", actual if not isinstance(actual, list) else f"{len(actual)} elements"))
        else:
            for i, (e, a) in enumerate(zip(expected, actual)):
                self._inline(e, a, f"{path}[{i}]", nan_payload, out)

    def _inline(self, expected, actual, path: str, nan_payload: bool, out: list) -> None:
        if expected is None or actual is None:
            if expected is not actual:
                out.append(Difference(path, expected and expected["abbrev"], actual, "null inline message"))
            return
        if not isinstance(actual, dict) or actual.get("abbrev") != expected["abbrev"]:
            out.append(Difference(path, expected["abbrev"], actual.get("abbrev") if isinstance(actual, dict) else actual, "message type"))
            return
        self._fields(self.defs[expected["abbrev"]], expected["fields"], actual.get("fields"), f"{path}.{expected['abbrev']}", nan_payload, out)


def _same_float(expected, actual, width: int, nan_payload: bool) -> bool:
    try:
        a = float_to_bits(actual, width)
    except ValueError:
        return False
    e = float_to_bits(expected, width)
    if not nan_payload and _is_nan(e, width) and _is_nan(a, width):
        return True
    return a == e


def _is_nan(bits: int, width: int) -> bool:
    exp_mask, frac_mask = ((0x7F800000, 0x007FFFFF) if width == 4 else (0x7FF0000000000000, 0x000FFFFFFFFFFFFF))
    return bits & exp_mask == exp_mask and bool(bits & frac_mask)

