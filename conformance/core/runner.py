"""Run selected cases through a session and build the result model. The one execution path: the CLI, the
pytest plugin, the benchmark and the tests all run cases here; the session does all the I/O."""

from __future__ import annotations

import datetime as dt
import time
from collections import Counter, defaultdict
from typing import Callable

from .cases import Case, expectation
from .hello import check_hello
from .results import CaseResult, CheckResult, Judgement, MessageResult, RunResult, message_verdict
from .session import Answer, Job, Session
from .suite import Suite
from .verdicts import Verdict, failing, worst
from .waivers import Waiver


def run_cases(session: Session, suite: Suite, cases: list[Case], *, edition: str, adapter: str,
              errata: str | None = None, waivers: dict[str, Waiver] | None = None, strict: bool = False,
              notes: list[str] | None = None, progress: Callable[[int], None] | None = None,
              options: dict | None = None, clock: Callable[[], float] = time.perf_counter,
              started: str | None = None) -> RunResult:
    """Judge every case; ``progress(n)`` is called as answers arrive (n = jobs done so far).

    ``options``: the run's settings the case kinds read (e.g. a scenario's parameters, allowed effects). A kind
    may decline a case (``admit``: the reason, listed in the notes) and may plan a request no implementation
    is asked (op ``skip``: judged at once, e.g. INCONCLUSIVE for a parameter not given). Cases of kinds the
    session does not run (its hello's ``kinds``) are left out, with a note. ``clock`` and ``started`` time the
    run (a session on virtual time passes its own, so that a rerun gives the same result to the byte).

    Ctrl-C (KeyboardInterrupt) while cases run ends the run early: the result then holds the cases whose
    every check was answered and is marked incomplete. ``errata`` names the implementation errata that
    annotate failures (default: the key the adapter's hello declares, if any).
    """
    started = started or dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds")
    began = clock()
    hello = check_hello(session.hello(), suite.name, suite.encoding_param + "s", suite.encodings)
    emits = set(hello["emits"])
    errata = errata or hello["errata"]
    options = options or {}
    notes = list(notes or [])
    groups = {g.name: g for g in suite.groups}
    cases = [c for c in cases if expectation(c.data, edition) is not None]  # a case may exist in one edition only
    strays = sorted({c.group for c in cases} - set(groups))
    if strays:  # never judge a case and leave it out of the result
        raise ValueError(f"cases filed under {', '.join(strays)}, which the suite {suite.name!r} does not have")
    cases, why = admitted(suite, cases, hello["kinds"], options)
    notes += why
    plans = {c.id: suite.kinds[c.kind].plan(c.data, edition, emits, options) for c in cases}
    by_id = {c.id: c for c in cases}
    jobs = [Job(f"{c.id}#{r.check}", suite.name, c.id, r) for c in cases for r in plans[c.id]]
    results: dict[str, list[CheckResult]] = defaultdict(list)
    timelines: dict[str, list[dict]] = {}
    answered: Counter = Counter()

    def judge(job: Job, answer: Answer) -> None:
        case = by_id[job.case_id]
        judged = suite.kinds[case.kind].judge(case.data, edition, job.request, answer)
        if isinstance(judged, Judgement):
            results[case.id] += judged.checks
            timelines[case.id] = judged.timeline
        else:
            results[case.id].append(judged)
        answered[case.id] += 1

    complete = True
    try:
        for job in jobs:
            if job.request.op == "skip":
                judge(job, Answer("skipped", reason=job.request.params.get("reason", "")))
        live = [job for job in jobs if job.request.op != "skip"]
        for done, (job, answer) in enumerate(session.run(live), 1):
            judge(job, answer)
            if progress:
                progress(done)
    except KeyboardInterrupt:
        complete = False
    if not complete:
        cases = [c for c in cases if plans[c.id] and answered[c.id] == len(plans[c.id])]
        notes.insert(0, f"interrupted: {len(cases)} of {len(plans)} cases were done; the others are not in this result")
    untested, why = hello_gaps(suite, cases, edition, emits, plans)
    notes += why + list(getattr(session, "notes", ()))
    waivers = waivers or {}
    filed: dict[str, list[CaseResult]] = defaultdict(list)
    for case in cases:
        own = [r for r in results.get(case.id, ()) if r.filed_under is None]
        checks = own if case.id in timelines else sorted(own, key=lambda r: r.check)
        verdict = worst(r.verdict for r in checks)
        waiver = waivers.get(case.id)
        if waiver is not None:
            verdict = Verdict.WAIVED if failing(verdict, strict=True) else Verdict.WAIVER_STALE
        explained = (suite.implementation_errata(case.id, errata, case.data.get("tags", ()))
                     if failing(verdict, strict=False) else [])
        filed[case.group].append(CaseResult(case.id, case.group, verdict, expectation(case.data, edition),
                                            case.data["clause"], checks, case.data.get("rule"), explained,
                                            waiver.reason if waiver else None, timelines.get(case.id, [])))
        for group, found in findings_elsewhere(results.get(case.id, ()), groups).items():
            case_id = f"{suite.name}/{group}/passive/{case.id.split('/', 1)[1]}"
            filed[group].append(CaseResult(case_id, group, worst(r.verdict for r in found), None, found[0].clause or "",
                                           found))
    messages = [MessageResult(g.name, g.key, message_verdict(filed[g.name], strict), filed[g.name])
                for g in suite.groups if g.name in filed]
    return RunResult(suite.name, suite.title, edition, hello["implementation"], adapter, strict, started,
                     round(clock() - began, 3), messages, session.stderr, notes, complete,
                     list(session.incidents), untested)


def admitted(suite: Suite, cases: list[Case], kinds: list[str], options: dict) -> tuple[list[Case], list[str]]:
    """The cases to run: those of the kinds the session runs that their kind admits; and notes on the rest."""
    out, declined, other = [], defaultdict(list), Counter()
    for case in cases:
        if case.kind not in kinds:
            other[case.kind] += 1
            continue
        reason = getattr(suite.kinds[case.kind], "admit", lambda *_: None)(case.data, options)
        if reason:
            declined[reason].append(case.id)
        else:
            out.append(case)
    notes = [f"{sum(other.values())} cases not run ({', '.join(f'{n} {kind}' for kind, n in sorted(other.items()))}): "
             f"the session runs {' and '.join(kinds)} cases"] if other else []
    notes += [f"{len(ids)} not run ({reason}): {', '.join(ids[:6])}{' ...' if len(ids) > 6 else ''}"
              for reason, ids in declined.items()]
    return out, notes


def findings_elsewhere(checks, groups: dict) -> dict[str, list[CheckResult]]:
    """The checks a case filed under other groups (e.g. the bytes of a reply, under the reply's message)."""
    out: dict[str, list[CheckResult]] = defaultdict(list)
    for check in checks:
        if check.filed_under is not None:
            if check.filed_under not in groups:
                raise ValueError(f"a finding filed under {check.filed_under!r}, which the suite does not have")
            out[check.filed_under].append(check)
    return out


def hello_gaps(suite: Suite, cases: list[Case], edition: str, emits: set[str], plans: dict) -> tuple[list[str], list[str]]:
    """The check kinds the hello rules out for every case (untested), and notes on what it narrows; ``plans``:
    the requests planned for what the implementation emits."""
    every = set(suite.encodings)
    if emits == every:
        return [], []
    wanted = Counter(r.check for c in cases for r in suite.kinds[c.kind].plan(c.data, edition, every, {}))
    planned = {r.check for c in cases for r in plans[c.id]}
    missing = sorted(check for check in wanted if check not in planned)
    if not missing:
        return [], []
    ops = sorted({check.split("-")[0] for check in missing})
    untested = [op for op in ops if not any(check.split("-")[0] == op for check in planned)]
    skipped = sum(wanted[check] for check in missing)
    if untested:
        note = (" and ".join(f"no {op} check ran" for op in untested) + f": the adapter's hello lists no "
                f"{suite.encoding_param.replace('_', ' ')} the implementation emits ({skipped} checks skipped; under "
                "--strict this fails the run)")
    else:
        note = (f"{', '.join(missing)} checks do not apply: the implementation emits only "
                f"{', '.join(sorted(emits))} ({skipped} checks skipped)")
    return untested, [note]
