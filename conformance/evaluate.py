"""Sans-IO judgement of one vector against an implementation's answers.

``plan`` lists the requests a case needs (which checks apply to this implementation and edition);
the caller performs them through an adapter and hands each ``Answer`` to ``judge``, which returns
the check's verdict. Nothing here does I/O.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

from .codec import EncodeError, encode, layout
from .compare import Comparator
from .decoded_form import message_problem
from .definitions import Definitions


class Verdict(str, Enum):
    PASS = "PASS"
    FAIL = "FAIL"
    NON_STRICT = "NON_STRICT"  # right outcome, but the rejection named the wrong rule
    IMPL_DEFINED = "IMPL_DEFINED"  # an acceptable case: recorded with what the implementation did
    UNSUPPORTED = "UNSUPPORTED"
    CRASH = "CRASH"
    TIMEOUT = "TIMEOUT"
    ADAPTER_ERROR = "ADAPTER_ERROR"
    WAIVED = "WAIVED"  # a failure a waiver covers
    WAIVER_STALE = "WAIVER_STALE"  # a waived case that now passes: the waiver must go


@dataclass(slots=True)
class Request:
    check: str  # "encode-le", "decode-be", "roundtrip-le", ...
    op: str  # "encode" | "decode" | "roundtrip"
    byte_order: str


@dataclass(slots=True)
class Answer:
    """What the implementation did: ``ok`` with a frame or message, or a refusal, or a failure to answer."""

    kind: str  # "ok" | "rejected" | "unsupported" | "crash" | "timeout" | "adapter-error"
    frame: bytes | None = None
    message: dict | None = None
    reason: str = ""
    rule: str | None = None
    note: str = ""  # how the answer was obtained, when that matters (e.g. replayed after a protocol violation)


@dataclass(frozen=True)
class ByteDiff:
    """Bytes ``[start, end)`` differ between the expected and actual frame; ``field`` owns them in the expected one."""

    start: int
    end: int
    field: str


@dataclass(slots=True)
class CheckResult:
    check: str
    verdict: Verdict
    detail: str
    outcome: str | None = None  # for acceptable cases: which permitted outcome the implementation chose
    expected: str | None = None  # hex frames, kept for failures so reports can show them side by side
    actual: str | None = None
    diffs: tuple[ByteDiff, ...] = ()
    note: str | None = None  # a remark on how the answer was obtained (Answer.note)


FAILURE_KINDS = {"crash": Verdict.CRASH, "timeout": Verdict.TIMEOUT, "adapter-error": Verdict.ADAPTER_ERROR,
                 "unsupported": Verdict.UNSUPPORTED}


def expectation(case: dict, edition: str) -> str | None:
    """``valid`` / ``invalid`` / ``acceptable`` under ``edition``; None if the case is not part of it."""
    expect = case["expect"]
    return expect if isinstance(expect, str) else expect.get(edition)


def plan(case: dict, edition: str, emits: set[str]) -> list[Request]:
    """The requests to make for ``case``; encoding in an order the implementation does not emit is not applicable."""
    if expectation(case, edition) is None:
        return []
    out = []
    for check in case["checks"]:
        if check == "roundtrip":
            out += [Request(f"roundtrip-{o}", "roundtrip", o) for o in ("le", "be") if o in emits and o in case["frames"]]
            continue
        op, order = check.split("-")
        if op == "encode" and order not in emits:
            continue
        out.append(Request(check, op, order))
    return out


class Judge:
    """Turns answers into verdicts for cases of one definitions set and its rules."""

    def __init__(self, defs: Definitions, rules: frozenset[str] | None = None):
        from .corpus.coverage import load_rules

        self.defs = defs
        self.rules = rules if rules is not None else frozenset(r["id"] for r in load_rules())
        self.compare = Comparator(defs)

    def judge(self, case: dict, edition: str, request: Request, answer: Answer) -> CheckResult:
        result = self._judge(case, edition, request, answer)
        if answer.note:
            result.note = answer.note
        return result

    def _judge(self, case: dict, edition: str, request: Request, answer: Answer) -> CheckResult:
        if answer.kind in FAILURE_KINDS:
            return CheckResult(request.check, FAILURE_KINDS[answer.kind], answer.reason)
        if answer.kind == "rejected" and answer.rule is not None and answer.rule not in self.rules:
            return CheckResult(request.check, Verdict.ADAPTER_ERROR, f"the refusal names the rule {answer.rule[:80]!r}, "
                               f"which rules.json does not have: {answer.reason}")
        expect = expectation(case, edition)
        if expect == "valid":
            return self._valid(case, request, answer)
        if expect == "invalid":
            return self._invalid(case, request, answer)
        return self._acceptable(case, request, answer)

    def _valid(self, case, request, answer) -> CheckResult:
        check = request.check
        if answer.kind == "rejected":
            return CheckResult(check, Verdict.FAIL, f"refused a valid {request.op}: {answer.reason}")
        expected = bytes.fromhex(case["frames"][request.byte_order])
        if request.op == "decode":
            diffs = self.compare.messages(case["message"], answer.message,
                                          nan_payload=case.get("compare", {}).get("nan_payload", False))
            if diffs and (malformed := self.malformed(answer.message)):
                return CheckResult(check, Verdict.ADAPTER_ERROR, malformed)
            if diffs:
                return self.failure(check, "; ".join(str(d) for d in diffs[:5]), expected,
                                    self.reencoded(answer.message, request.byte_order))
            return CheckResult(check, Verdict.PASS, "decoded as expected")
        if answer.frame != expected:
            return self.failure(check, "", expected, answer.frame, locate=True)
        return CheckResult(check, Verdict.PASS, "frame matches" if request.op == "encode" else "re-encoded to the same frame")

    def _invalid(self, case, request, answer) -> CheckResult:
        check, rule = request.check, case["rule"]
        if answer.kind == "ok":
            what = "accepted an invalid frame" if request.op == "decode" else "encoded a message it must refuse"
            return CheckResult(check, Verdict.FAIL, f"{what} (rule {rule})")
        if answer.rule is not None and answer.rule != rule:
            return CheckResult(check, Verdict.NON_STRICT, f"rejected, but named rule {answer.rule!r} instead of {rule!r}: {answer.reason}")
        return CheckResult(check, Verdict.PASS, f"rejected: {answer.reason}")

    def _acceptable(self, case, request, answer) -> CheckResult:
        check = request.check
        permitted = {o["outcome"]: o for o in case["outcomes"]}
        if answer.kind == "rejected":
            if "reject" in permitted and answer.rule is not None:
                return CheckResult(check, Verdict.NON_STRICT, f"rejected naming rule {answer.rule!r}, which this case "
                                   f"does not break: {answer.reason}", "reject")
            if "reject" in permitted:
                return CheckResult(check, Verdict.IMPL_DEFINED, f"rejected: {answer.reason}", "reject")
            return CheckResult(check, Verdict.FAIL, f"rejected, which this case does not permit: {answer.reason}")
        if request.op == "decode":
            diffs = self.compare.messages(case["message"], answer.message,
                                          nan_payload=case.get("compare", {}).get("nan_payload", False))
            if diffs and (malformed := self.malformed(answer.message)):
                return CheckResult(check, Verdict.ADAPTER_ERROR, malformed)
            if not diffs and "accept" in permitted:
                return CheckResult(check, Verdict.IMPL_DEFINED, "accepted", "accept")
            expected = bytes.fromhex(case["frames"][request.byte_order])
            return self.failure(check, "accepted, but decoded wrongly: " + "; ".join(str(d) for d in diffs[:5]),
                                expected, self.reencoded(answer.message, request.byte_order))
        frames = {name: o.get("frames", case.get("frames")) for name, o in permitted.items() if name != "reject"}
        for name, candidate in frames.items():
            if candidate and candidate.get(request.byte_order) == (answer.frame or b"").hex():
                return CheckResult(check, Verdict.IMPL_DEFINED, f"{name}: {answer.frame.hex()[:64]}", name)
        reference = bytes.fromhex((frames.get("accept") or next(iter(frames.values()), {}))[request.byte_order])
        return self.failure(check, "encoded to a frame no outcome permits: ", reference, answer.frame, locate=True)

    def malformed(self, message) -> str | None:
        """Why an answered message is not a well-formed decoded form (the adapter's fault), or None."""
        problem = message_problem(self.defs, message, whole_header=True, in_range=False)
        return None if problem is None else f"malformed answer: message{problem[0]}: {problem[1]}"

    def failure(self, check: str, detail: str, expected: bytes, actual: bytes | None, locate: bool = False) -> CheckResult:
        """A FAIL that keeps both frames and the differing byte ranges, named by field; ``locate`` adds where
        the frames first differ to ``detail``. The expected frame is laid out once."""
        spans = self._spans(expected) if actual is not None else []
        if locate:
            detail += self.frame_difference(expected, actual, spans)
        return CheckResult(check, Verdict.FAIL, detail, expected=expected.hex(),
                           actual=None if actual is None else actual.hex(), diffs=self.byte_diffs(expected, actual, spans))

    def _spans(self, frame: bytes) -> list:
        try:
            return layout(self.defs, frame)
        except ValueError:  # an expected frame the codec cannot lay out (e.g. an out-of-type alternative)
            return []

    def reencoded(self, message, byte_order: str) -> bytes | None:
        """The reference encoding of an implementation's decoded message, to show what it understood."""
        try:
            return encode(self.defs, message, byte_order)
        except (EncodeError, KeyError, TypeError, AttributeError):
            return None

    @staticmethod
    def byte_diffs(expected: bytes, actual: bytes | None, spans: list) -> tuple[ByteDiff, ...]:
        """Runs of differing bytes, split at the field boundaries (``spans``) of the expected frame."""
        if actual is None:
            return ()
        owner = {i: s.path for s in spans for i in range(s.start, s.end)}
        out: list[ByteDiff] = []
        for i in range(max(len(expected), len(actual))):
            differs = i >= len(expected) or i >= len(actual) or expected[i] != actual[i]
            if not differs:
                continue
            name = owner.get(i, "beyond the expected frame" if i >= len(expected) else "unmapped")
            if out and out[-1].end == i and out[-1].field == name:
                out[-1] = ByteDiff(out[-1].start, i + 1, name)
            else:
                out.append(ByteDiff(i, i + 1, name))
        return tuple(out)

    @staticmethod
    def frame_difference(expected: bytes, actual: bytes | None, spans: list) -> str:
        """Where two frames first differ, named by the field (of ``spans``) that owns the byte in the expected frame."""
        if actual is None:
            return "no frame"
        first = next((i for i, (a, b) in enumerate(zip(expected, actual)) if a != b), min(len(expected), len(actual)))
        if first == len(expected) == len(actual):
            return "identical"
        owner = next((s for s in spans if s.start <= first < s.end), None)
        where = f" = {owner.path} (bytes {owner.start}-{owner.end - 1})" if owner else ""
        return (f"{len(actual)} bytes, expected {len(expected)}; first difference at byte {first}{where}: "
                f"expected {expected[first:first + 8].hex(' ')}, got {actual[first:first + 8].hex(' ')}")


SEVERITY = {v: rank for rank, v in enumerate([
    Verdict.CRASH, Verdict.TIMEOUT, Verdict.ADAPTER_ERROR, Verdict.FAIL, Verdict.NON_STRICT,
    Verdict.IMPL_DEFINED, Verdict.UNSUPPORTED, Verdict.PASS])}


def worst(results: list[CheckResult]) -> Verdict:
    """The case verdict: the most severe of its checks (UNSUPPORTED if none)."""
    return min((r.verdict for r in results), key=SEVERITY.__getitem__, default=Verdict.UNSUPPORTED)
