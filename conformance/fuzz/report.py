"""A fuzzing run in the one result model, so that every renderer reports it as it reports ``run``.

Each finding is a case (``<suite>/<group>/fuzz/<hash>``) whose checks are every implementation's checks, their
detail starting with the implementation's name, with the classification as their note; a group and property (or
sweep) with no finding is one PASS case (``<suite>/<group>/fuzz/<property>``) saying how many examples were judged.
"""

from __future__ import annotations

from collections import defaultdict

from ..core.results import CaseResult, CheckResult, MessageResult, RunResult, message_verdict
from ..core.verdicts import Verdict, failing, worst


def finding_case(finding) -> CaseResult:
    """A finding as a case; every check keeps the frame it was given (the input that caused a crash too)."""
    frames = finding.case.get("frames", {})
    checks = []
    for name, result in finding.results.items():
        for c in result.checks:
            given = c.expected or frames.get(c.check.rpartition("-")[2]) or next(iter(frames.values()), None)
            checks.append(CheckResult(c.check, c.verdict, f"{name}: {c.detail}", c.outcome, given, c.actual,
                                      c.diffs, finding.classification, c.clause))
    deviating = [finding.results[n] for n in finding.deviating]
    verdict = worst(r.verdict for r in deviating) if deviating else Verdict.PASS
    errata = sorted({e for r in deviating for e in r.errata})
    explained = errata if deviating and all(r.errata for r in deviating) else []
    case = finding.case
    return CaseResult(case["id"], finding.group, verdict, next(iter(case["expect"].values())), case["clause"], checks,
                      case.get("rule"), explained)


def fuzz_result(suite, source, tally, names: list[str], implementations: list[str], edition: str, *, started: str,
                duration: float, notes: list[str]) -> RunResult:
    filed: dict[str, list[CaseResult]] = defaultdict(list)
    found = defaultdict(int)
    for finding in tally.findings:
        filed[finding.group].append(finding_case(finding))
        found[finding.case["id"].split("/")[1], finding.prop] += 1
    for (group, prop), judged in tally.judged.items():
        if not found[group, prop]:
            verdict, detail = _agreement(tally, (group, prop), names, judged,
                                         "messages" if prop == "message" else "frames")
            filed[group].append(CaseResult(f"{suite.name}/{group}/fuzz/{prop}", group, verdict, None,
                                           source.clause(group), [CheckResult(f"fuzz:{prop}", verdict, detail)]))
    messages = [MessageResult(g.name, g.key, message_verdict(filed[g.name], False), filed[g.name])
                for g in suite.groups if g.name in filed]
    return RunResult(suite.name, suite.title, edition, " vs ".join(implementations), ",".join(names), False, started,
                     round(duration, 3), messages, "", notes)


def _agreement(tally, key: tuple[str, str], names: list[str], judged: int, what: str) -> tuple[Verdict, str]:
    """The verdict and detail of a group and property without a finding: PASS where some implementation was tested
    on its examples, naming any that answered every one untested (UNSUPPORTED: never agreement); UNSUPPORTED where
    none was."""
    sent, untested = tally.sent[key], tally.untested.get(key, {})
    idle = [n for n in names if sent and untested.get(n, 0) == sent]
    if not sent or len(idle) == len(names):
        who = "the implementation" if len(names) == 1 else "every implementation"
        return Verdict.UNSUPPORTED, (f"{judged} generated {what}: {who} answered every one unsupported (or could not "
                                     "be tested): nothing was compared with the reference")
    tested = [n for n in names if n not in idle]
    agree = f"{'every implementation agrees' if len(names) > 1 else names[0] + ' agrees'} with the reference"
    if idle:
        agree = (f"{', '.join(tested)} {'agrees' if len(tested) == 1 else 'agree'} with the reference; "
                 f"{', '.join(idle)} answered every one unsupported: not tested")
    partly = sum(untested.get(n, 0) for n in tested)
    return Verdict.PASS, f"{judged} generated {what} judged: {agree}" + (
        f" ({partly} of the answers were unsupported: those not compared)" if partly else "")


def unexplained(tally) -> int:
    """Findings some implementation fails with no documented erratum to explain it (the run then exits 1)."""
    return sum(1 for f in tally.findings if f.unexplained)


def review(results: dict) -> list[str]:
    """Corpus vectors every implementation fails with no erratum explaining it: flagged for review (the vector or
    the reference may be what is wrong)."""
    failed = None
    for result in results.values():
        ids = {c.id for c in result.cases if failing(c.verdict, strict=False) and not c.errata}
        failed = ids if failed is None else failed & ids
    return sorted(failed or ())
