"""Run selected cases through a session and build the result model; the session does all the I/O."""

from __future__ import annotations

import datetime as dt
import time
from collections import Counter, defaultdict
from typing import Callable

from .corpus_data import implementation_errata
from .definitions import Definitions
from .evaluate import CheckResult, Judge, Verdict, expectation, plan, worst
from .hello import ORDERS, check_hello
from .results import CaseResult, MessageResult, RunResult, failing, message_verdict
from .session import Job, Session
from .waivers import Waiver

SUITE = "imc"


def run_cases(session: Session, cases: list[dict], *, defs: Definitions, edition: str, adapter: str,
              errata_name: str | None = None, waivers: dict[str, Waiver] | None = None, strict: bool = False,
              notes: list[str] | None = None, progress: Callable[[int], None] | None = None) -> RunResult:
    """Judge every case; ``progress(n)`` is called as answers arrive (n = jobs done so far).

    Ctrl-C (KeyboardInterrupt) while cases run ends the run early: the result then holds the cases whose
    every check was answered and is marked incomplete. ``errata_name`` selects the implementation errata that
    annotate failures (default: the first word of the implementation's name in its hello, e.g. ``imcpy``).
    """
    started = dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds")
    clock = time.perf_counter()
    hello = check_hello(session.hello(), SUITE)
    emits = set(hello["byte_orders"])
    implementation = hello["implementation"]
    errata_name = errata_name or implementation.split(" ", 1)[0]  # "imcpy 1.1.2 (...)" -> the errata of "imcpy"
    judge = Judge(defs)
    cases = [c for c in cases if expectation(c, edition) is not None]  # a case may exist in one edition only
    plans = {case["id"]: plan(case, edition, emits) for case in cases}
    jobs = [Job(f"{case['id']}#{request.check}", SUITE, case, request) for case in cases for request in plans[case["id"]]]
    results: dict[str, list[CheckResult]] = defaultdict(list)
    complete = True
    try:
        for done, (job, answer) in enumerate(session.run(jobs), 1):
            results[job.case["id"]].append(judge.judge(job.case, edition, job.request, answer))
            if progress:
                progress(done)
    except KeyboardInterrupt:
        complete = False
    notes = list(notes or [])
    if not complete:
        cases = [c for c in cases if plans[c["id"]] and len(results[c["id"]]) == len(plans[c["id"]])]
        notes.insert(0, f"interrupted: {len(cases)} of {len(plans)} cases were done; the others are not in this result")
    untested, why = hello_gaps(cases, edition, emits)
    notes += why
    waivers = waivers or {}
    by_message: dict[str, list[CaseResult]] = defaultdict(list)
    for case in cases:
        checks = sorted(results.get(case["id"], ()), key=lambda r: r.check)
        verdict = worst(checks) if checks else Verdict.UNSUPPORTED
        waiver = waivers.get(case["id"])
        if waiver is not None:
            verdict = Verdict.WAIVED if failing(verdict, strict=True) else Verdict.WAIVER_STALE
        errata = implementation_errata(case["id"], errata_name) if failing(verdict, strict=False) else []
        message = case["id"].split("/")[1]
        by_message[message].append(CaseResult(case["id"], message, verdict, expectation(case, edition), case["clause"],
                                              checks, case.get("rule"), errata, waiver.reason if waiver else None))
    messages = [MessageResult(m.abbrev, m.id, message_verdict(by_message[m.abbrev], strict), by_message[m.abbrev])
                for m in defs.suite_messages if m.abbrev in by_message]
    return RunResult(SUITE, edition, implementation, adapter, strict, started, time.perf_counter() - clock, messages,
                     session.stderr, notes, complete, list(session.incidents), untested)


def hello_gaps(cases: list[dict], edition: str, emits: set[str]) -> tuple[list[str], list[str]]:
    """The check kinds the hello rules out for every case (untested), and notes on what it narrows."""
    wanted = Counter(r.check for c in cases for r in plan(c, edition, set(ORDERS)))
    planned = {r.check for c in cases for r in plan(c, edition, emits)}
    missing = sorted(check for check in wanted if check not in planned)
    if not missing:
        return [], []
    ops = sorted({check.split("-")[0] for check in missing})
    untested = [op for op in ops if not any(check.startswith(op) for check in planned)]
    skipped = sum(wanted[check] for check in missing)
    if untested:
        note = (" and ".join(f"no {op} check ran" for op in untested) + ": the adapter's hello lists no byte order "
                f"the implementation emits ({skipped} checks skipped; under --strict this fails the run)")
    else:
        note = (f"{', '.join(missing)} checks do not apply: the implementation emits only "
                f"{', '.join(sorted(emits))} ({skipped} checks skipped)")
    return untested, [note]
