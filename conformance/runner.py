"""Run selected cases through a session and build the result model; the session does all the I/O."""

from __future__ import annotations

import datetime as dt
import time
from collections import defaultdict
from typing import Callable

from .corpus_data import implementation_errata
from .definitions import Definitions
from .evaluate import CheckResult, Judge, Verdict, expectation, plan, worst
from .results import FAILING, CaseResult, MessageResult, RunResult, message_verdict
from .session import Job, Session
from .waivers import Waiver


def run_cases(session: Session, cases: list[dict], *, defs: Definitions, edition: str, adapter: str,
              errata_name: str | None = None, waivers: dict[str, Waiver] | None = None, strict: bool = False,
              notes: list[str] | None = None, progress: Callable[[int], None] | None = None) -> RunResult:
    """Judge every case; ``progress(n)`` is called as answers arrive (n = jobs done so far).

    ``errata_name`` selects the implementation errata that annotate failures (default: the first word of
    the implementation's name in its hello, e.g. ``imcpy``).
    """
    started = dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds")
    clock = time.perf_counter()
    hello = session.hello()
    emits = set(hello.get("byte_orders", ()))
    implementation = str(hello.get("implementation", adapter))
    errata_name = errata_name or implementation.split(" ", 1)[0]  # "imcpy 1.1.2 (...)" -> the errata of "imcpy"
    judge = Judge(defs)
    cases = [c for c in cases if expectation(c, edition) is not None]  # a case may exist in one edition only
    jobs = [Job(f"{case['id']}#{request.check}", "imc", case, request)
            for case in cases for request in plan(case, edition, emits)]
    results: dict[str, list[CheckResult]] = defaultdict(list)
    for done, (job, answer) in enumerate(session.run(jobs), 1):
        results[job.case["id"]].append(judge.judge(job.case, edition, job.request, answer))
        if progress:
            progress(done)
    waivers = waivers or {}
    by_message: dict[str, list[CaseResult]] = defaultdict(list)
    for case in cases:
        checks = sorted(results.get(case["id"], ()), key=lambda r: r.check)
        verdict = worst(checks) if checks else Verdict.UNSUPPORTED
        waiver = waivers.get(case["id"])
        if waiver is not None:
            failing = verdict in FAILING or verdict is Verdict.NON_STRICT
            verdict = Verdict.WAIVED if failing else Verdict.WAIVER_STALE
        errata = implementation_errata(case["id"], errata_name) if verdict in FAILING else []
        message = case["id"].split("/")[1]
        by_message[message].append(CaseResult(case["id"], message, verdict, expectation(case, edition), case["clause"],
                                              checks, case.get("rule"), errata, waiver.reason if waiver else None))
    messages = [MessageResult(m.abbrev, m.id, message_verdict(by_message[m.abbrev], strict), by_message[m.abbrev])
                for m in defs.suite_messages if m.abbrev in by_message]
    return RunResult("imc", edition, implementation, adapter, strict, started,
                     time.perf_counter() - clock, messages, session.stderr, list(notes or []))
