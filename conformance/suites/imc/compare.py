"""Compare an implementation's decoded message with the expected one, as the corpus's policy says.

Values are compared at the field's width (a fp32 answered as the double 0.10000000149011612 equals
the expected 0.1); ``-0.0`` differs from ``0.0``; any NaN matches ``"nan"`` unless the case asks for
exact NaN payloads; plaintext compares as bytes (a string stands for its UTF-8 encoding).
"""

from __future__ import annotations

from .decoded_form import HEADER
from .definitions import Definitions, FieldDef, MessageDef
from ...kinds.vector.errors import Difference
from ...kinds.vector.floats import same_float
from .values import raw_bytes, text_bytes


_MISSING = object()


class Comparator:
    """Compares decoded messages against one set of definitions; per-message checkers are built once."""

    def __init__(self, defs: Definitions):
        self.defs = defs
        self._checkers: dict[str, list] = {}
        self._header = self._build(HEADER)

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
            self._check(self._header, expected["header"], header, "header", nan_payload, out, extra_ok=True)
        self._fields(expected["abbrev"], expected["fields"], actual.get("fields"), expected["abbrev"], nan_payload, out)
        return out

    def _fields(self, abbrev: str, expected: dict, actual, path: str, nan_payload: bool, out: list) -> None:
        if not isinstance(actual, dict):
            out.append(Difference(f"{path}.fields", "an object", actual))
            return
        checkers = self._checkers.get(abbrev)
        if checkers is None:
            checkers = self._checkers[abbrev] = self._build(self.defs[abbrev])
        self._check(checkers, expected, actual, path, nan_payload, out)

    @staticmethod
    def _check(checkers, expected: dict, actual: dict, path: str, nan_payload: bool, out: list, extra_ok=False) -> None:
        for name, check in checkers:
            value = actual.get(name, _MISSING)
            if value is _MISSING:
                out.append(Difference(f"{path}.{name}", expected[name], None, "missing"))
            else:
                check(expected[name], value, f"{path}.{name}", nan_payload, out)
        if not extra_ok and len(actual) != len(checkers):
            for extra in sorted(set(actual) - {name for name, _ in checkers}):
                out.append(Difference(f"{path}.{extra}", None, actual[extra], "not a field of " + path))

    def _build(self, mdef: MessageDef) -> list:
        """(field name, checker) per field; a checker appends Differences to ``out``."""
        return [(f.abbrev, self._checker(f)) for f in mdef.fields]

    def _checker(self, f: FieldDef):
        if f.is_float:
            width, type_ = f.size, f.type

            def check_float(e, a, path, nan_payload, out):
                if not same_float(e, a, width, nan_payload):
                    pinned = nan_payload and a == "nan" and isinstance(e, str) and e.startswith("nan:")
                    out.append(Difference(path, e, a, type_ + ('; this case pins the NaN\'s bits: answer "nan:<hex>"'
                                                               if pinned else "")))
            return check_float
        if f.is_int:
            type_ = f.type

            def check_int(e, a, path, nan_payload, out):
                if a != e or type(a) is not int:
                    out.append(Difference(path, e, a, type_))
            return check_int
        if f.type in ("plaintext", "rawdata"):
            convert, type_ = (text_bytes if f.type == "plaintext" else raw_bytes), f.type

            def check_bytes(e, a, path, nan_payload, out):
                if a == e:
                    return
                try:
                    same = convert(e) == convert(a)
                except (ValueError, TypeError):
                    same = False
                if not same:
                    out.append(Difference(path, e, a, type_))
            return check_bytes
        if f.type == "message":
            return self._inline

        def check_list(e, a, path, nan_payload, out):
            if not isinstance(a, list) or len(a) != len(e):
                out.append(Difference(path, f"{len(e)} elements", a if not isinstance(a, list) else f"{len(a)} elements"))
                return
            for i, (x, y) in enumerate(zip(e, a)):
                self._inline(x, y, f"{path}[{i}]", nan_payload, out)
        return check_list

    def _inline(self, expected, actual, path: str, nan_payload: bool, out: list) -> None:
        if expected is None or actual is None:
            if expected is not actual:
                out.append(Difference(path, expected and expected["abbrev"], actual, "null inline message"))
            return
        if not isinstance(actual, dict) or actual.get("abbrev") != expected["abbrev"]:
            out.append(Difference(path, expected["abbrev"], actual.get("abbrev") if isinstance(actual, dict) else actual, "message type"))
            return
        self._fields(expected["abbrev"], expected["fields"], actual.get("fields"), f"{path}.{expected['abbrev']}", nan_payload, out)
