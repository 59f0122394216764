"""What a suite's reference codec raises, and how a comparison reports a difference: shared by every suite."""

from __future__ import annotations

from dataclasses import dataclass


class FrameError(ValueError):
    """Bytes the codec rejects: ``rule`` is the rule id they break, ``offset`` where it was found, ``role`` what was
    being read (a length, count or inline id) when the bytes ran out, where the codec says."""

    def __init__(self, rule: str, offset: int, detail: str, role: str | None = None):
        super().__init__(f"{rule} at byte {offset}: {detail}")
        self.rule, self.offset, self.detail = rule, offset, detail
        self.role = role  # the part being read when the bytes ran out (a length, count or id), if known


class NotJudged(ValueError):
    """Bytes the reference codec does not judge, valid or not, because they lie beyond a bound the suite keeps
    (``reason``, e.g. ``nested-too-deep``): every path gives them the same verdict, INCONCLUSIVE."""

    def __init__(self, reason: str, offset: int, detail: str):
        super().__init__(f"{reason} at byte {offset}: {detail}")
        self.reason, self.offset, self.detail = reason, offset, detail


class EncodeError(ValueError):
    """A message the codec refuses to encode, with the rule id it would break."""

    def __init__(self, rule: str, detail: str):
        super().__init__(f"{rule}: {detail}")
        self.rule, self.detail = rule, detail


@dataclass(frozen=True)
class Difference:
    """Where an answered message differs from the expected one."""

    path: str
    expected: object
    actual: object
    why: str = ""

    def __str__(self) -> str:
        why = f" ({self.why})" if self.why else ""
        return f"{self.path}: expected {self.expected!r}, got {self.actual!r}{why}"
