"""Sans-IO judgement of one vector against an implementation's answers.

``plan`` lists the requests a case needs (which checks apply to this implementation and edition);
the caller performs them through an adapter and hands each ``Answer`` to ``judge``, which returns
the check's verdict. Nothing here does I/O.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

from .codec import layout
from .compare import Comparator
from .definitions import Definitions


class Verdict(str, Enum):
    PASS = "PASS"
    FAIL = "FAIL"
    NON_STRICT = "NON_STRICT"  # right outcome, wrong rule named
    IMPL_DEFINED = "IMPL_DEFINED"
    UNSUPPORTED = "UNSUPPORTED"
    CRASH = "CRASH"
    TIMEOUT = "TIMEOUT"
    ADAPTER_ERROR = "ADAPTER_ERROR"


@dataclass(frozen=True)
class Request:
    check: str  # "encode-le", "decode-be", "roundtrip-le", ...
    op: str  # "encode" | "decode" | "roundtrip"
    byte_order: str


@dataclass(frozen=True)
class Answer:
    """What the implementation did: ``ok`` with a frame or message, or a refusal, or a failure to answer."""

    kind: str  # "ok" | "rejected" | "unsupported" | "crash" | "timeout" | "adapter-error"
    frame: bytes | None = None
    message: dict | None = None
    reason: str = ""
    rule: str | None = None


@dataclass(frozen=True)
class CheckResult:
    check: str
    verdict: Verdict
    detail: str
    outcome: str | None = None  # for acceptable cases: which permitted outcome the implementation chose


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
    """Turns answers into verdicts for cases of one definitions set."""

    def __init__(self, defs: Definitions):
        self.defs = defs
        self.compare = Comparator(defs)

    def judge(self, case: dict, edition: str, request: Request, answer: Answer) -> CheckResult:
        if answer.kind in FAILURE_KINDS:
            return CheckResult(request.check, FAILURE_KINDS[answer.kind], answer.reason)
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
        if request.op == "decode":
            diffs = self.compare.messages(case["message"], answer.message,
                                          nan_payload=case.get("compare", {}).get("nan_payload", False))
            if diffs:
                return CheckResult(check, Verdict.FAIL, "; ".join(str(d) for d in diffs[:5]))
            return CheckResult(check, Verdict.PASS, "decoded as expected")
        expected = bytes.fromhex(case["frames"][request.byte_order])
        if answer.frame != expected:
            return CheckResult(check, Verdict.FAIL, self.frame_difference(expected, answer.frame))
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
            if "reject" in permitted:
                return CheckResult(check, Verdict.IMPL_DEFINED, f"rejected: {answer.reason}", "reject")
            return CheckResult(check, Verdict.FAIL, f"rejected, which this case does not permit: {answer.reason}")
        if request.op == "decode":
            diffs = self.compare.messages(case["message"], answer.message,
                                          nan_payload=case.get("compare", {}).get("nan_payload", False))
            if not diffs and "accept" in permitted:
                return CheckResult(check, Verdict.IMPL_DEFINED, "accepted", "accept")
            return CheckResult(check, Verdict.FAIL, "accepted, but decoded wrongly: " + "; ".join(str(d) for d in diffs[:5]))
        frames = {name: o.get("frames", case.get("frames")) for name, o in permitted.items() if name != "reject"}
        for name, candidate in frames.items():
            if candidate and candidate.get(request.byte_order) == (answer.frame or b"").hex():
                return CheckResult(check, Verdict.IMPL_DEFINED, f"{name}: {answer.frame.hex()[:64]}", name)
        reference = (frames.get("accept") or next(iter(frames.values()), {})).get(request.byte_order)
        detail = self.frame_difference(bytes.fromhex(reference), answer.frame) if reference else "no permitted frame"
        return CheckResult(check, Verdict.FAIL, "encoded to a frame no outcome permits: " + detail)

    def frame_difference(self, expected: bytes, actual: bytes | None) -> str:
        """Where two frames first differ, named by the field that owns the byte in the expected frame."""
        if actual is None:
            return "no frame"
        first = next((i for i, (a, b) in enumerate(zip(expected, actual)) if a != b), min(len(expected), len(actual)))
        if first == len(expected) == len(actual):
            return "identical"
        try:
            owner = next((s for s in layout(self.defs, expected) if s.start <= first < s.end), None)
        except ValueError:
            owner = None
        where = f" = {owner.path} (bytes {owner.start}-{owner.end - 1})" if owner else ""
        return (f"{len(actual)} bytes, expected {len(expected)}; first difference at byte {first}{where}: "
                f"expected {expected[first:first + 8].hex(' ')}, got {actual[first:first + 8].hex(' ')}")


def worst(results: list[CheckResult]) -> Verdict:
    """The case verdict: the most severe of its checks."""
    order = [Verdict.CRASH, Verdict.TIMEOUT, Verdict.ADAPTER_ERROR, Verdict.FAIL, Verdict.NON_STRICT,
             Verdict.IMPL_DEFINED, Verdict.UNSUPPORTED, Verdict.PASS]
    present = {r.verdict for r in results}
    return next((v for v in order if v in present), Verdict.UNSUPPORTED)
