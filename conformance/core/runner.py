"""Run selected cases through a session and build the result model. The one execution path: the CLI, the
pytest plugin, the benchmark and the tests all run cases here; the session does all the I/O."""

from __future__ import annotations

import datetime as dt
import gc
import time
from collections import Counter, defaultdict
from dataclasses import replace
from typing import Callable

from .cases import Case, expectation, passive_id
from .evidence import Evidence
from .causes import about, cause_of, described, group_causes
from .hello import check_hello
from .results import CaseResult, CheckResult, Judgement, MessageResult, Provenance, RunResult, message_verdict
from .session import Answer, Job, Session
from .suite import Suite
from .verdicts import UNTESTED, Verdict, failing, worst
from .waivers import NEVER, Waiver, Waivers, stale_note, waivable


PROGRESS_EVERY = 64  # answers between calls of a run's progress callback


def run_cases(session: Session, suite: Suite, cases: list[Case], *, edition: str, adapter: str,
              errata: str | None = None, waivers: Waivers | None = None, strict: bool = False,
              notes: list[str] | None = None, progress: Callable[[int], None] | None = None,
              options: dict | None = None, clock: Callable[[], float] = time.perf_counter,
              started: str | None = None, provenance: Provenance | None = None, exitfirst: bool = False,
              shard: tuple[int, int] | None = None, selection: list[Case] | None = None,
              corpus: list[Case] | None = None, evidence: bool = True) -> RunResult:
    """Judge every case; ``progress(n)`` is called as answers arrive (n = jobs done so far, every
    ``PROGRESS_EVERY`` answers and at the end).

    ``options``: the run's settings the case kinds read (e.g. a scenario's parameters, allowed effects). A kind
    may decline a case (``admit``: the reason, listed in the notes) and may plan a request no implementation
    is asked (op ``skip``: judged at once, e.g. INCONCLUSIVE for a parameter not given). Cases of kinds the
    session does not run (its hello's ``kinds``) are left out, with a note. ``clock`` and ``started`` time the
    run (a session on virtual time passes its own, so that a rerun gives the same result to the byte).

    Ctrl-C (KeyboardInterrupt) while cases run ends the run early: the result then holds the cases whose
    every check was answered and is marked incomplete. ``errata`` names the implementation errata that
    annotate failures (default: the key the adapter's hello declares, if any); ``provenance`` (what the command
    line records of the run) is the result's, with that key.

    ``exitfirst``: the run stops once a case is done and fails (its verdict, or a finding it filed elsewhere): the
    result holds the cases done by then, with a note naming that case.

    ``shard``: (K, N) of a run of one shard of ``selection`` (every case of the run's selection): a broad waiver
    naming cases of the selection that waives none of the shard's is noted, and left to the merge of the shards
    (another shard may use it; the merge finds it stale when no shard does).

    ``evidence``: a refusal counts only from an implementation shown to do what it refuses (see ``Evidence``);
    ``corpus`` (the cases loaded, of which ``cases`` are a selection): where the selection shows nothing of a group,
    the base a refused case names (else a valid case of its group) is asked too. False: each refusal is judged alone
    (a fuzzer's generated frames, whose deviations are what it reports).

    The cyclic garbage collector is paused while the run lasts: a run makes little cyclic garbage, and each full
    collection would walk the whole loaded corpus again.
    """
    collecting = gc.isenabled()
    gc.disable()
    try:
        return _run(session, suite, cases, edition, adapter, errata, waivers, strict, notes, progress, options, clock,
                    started, provenance, exitfirst, shard, selection, corpus, evidence)
    finally:
        if collecting:
            gc.enable()


def _run(session, suite, cases, edition, adapter, errata, waivers, strict, notes, progress, options, clock,
         started, provenance, exitfirst, shard, selection, corpus, evidence) -> RunResult:
    started = started or dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds")
    began = clock()
    hello = check_hello(session.hello(), suite.name, suite.encoding_param + "s", suite.encodings)
    emits = frozenset(hello["emits"])
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
    kinds, name = suite.kinds, suite.name
    plans = {c.id: kinds[c.kind].plan(c.data, edition, emits, options) for c in cases}
    jobs = [Job(name, c.id, r) for c in cases for r in plans[c.id]]
    # per case: its data, how it is judged, and what its checks found (judged in place as answers come)
    judges = {c.id: (c.data, kinds[c.kind].judge, []) for c in cases}
    weigh = Evidence(suite, cases, edition) if evidence else None
    timelines: dict[str, list[dict]] = {}
    answered: list[str] = []  # the case of each job answered (counted if the run is interrupted)
    waivers = waivers or Waivers()
    left = Counter(job.case_id for job in jobs) if exitfirst else None  # jobs unanswered, per case
    stopped_at: list[str] = []  # the failing case the run stopped at (exitfirst)

    def judge(job: Job, answer: Answer) -> None:
        data, judge_, found = judges[job.case_id]
        judged = judge_(data, edition, job.request, answer)
        if judged.__class__ is Judgement:
            found += judged.checks
            timelines[job.case_id] = judged.timeline
        else:
            found.append(judged)
            if weigh is not None:
                weigh.answered(job, answer, judged)
        answered.append(job.case_id)
        if left is not None:
            left[job.case_id] -= 1
            if not left[job.case_id] and _fails(name, job.case_id, data, edition, found, waivers, strict):
                stopped_at.append(job.case_id)

    complete = True
    try:
        for job in jobs:
            if job.request.op == "skip" and not stopped_at:
                judge(job, Answer("skipped", reason=job.request.params.get("reason", "")))
        live = [job for job in jobs if job.request.op != "skip"]
        asked = weigh.plan(corpus or (), plans, emits) if weigh is not None and live else []
        done = 0
        answers = session.run(asked + live if not stopped_at else [])
        for done, (job, answer) in enumerate(answers, 1):
            if asked and id(job) in weigh.probes:
                weigh.answered(job, answer)
                continue
            judge(job, answer)
            if progress and not done % PROGRESS_EVERY:
                progress(done)
            if stopped_at:
                if hasattr(answers, "close"):  # a generator: what is still in flight is left unanswered
                    answers.close()
                break
        if progress:
            progress(done)
    except KeyboardInterrupt:
        complete = False
    if not complete or stopped_at:
        counts = Counter(answered)
        cases = [c for c in cases if plans[c.id] and counts[c.id] == len(plans[c.id])]
        notes.insert(0, (f"stopped at the first failing case, {stopped_at[0]}" if complete else "interrupted")
                     + f": {len(cases)} of {len(plans)} cases were done; the others are not in this result")
    if weigh is not None:
        weigh.review({case_id: found for case_id, (_, _, found) in judges.items()})
    untested, why = hello_gaps(suite, cases, edition, emits, plans)
    if waivers and cases and all(worst({r.verdict for r in judges[c.id][2]}) in (*UNTESTED, *NEVER) for c in cases):
        waivers = Waivers()  # nothing judged: no failure to waive (the run says why nothing could be tested)
        notes.append("no waiver applies: the run judged nothing")
    notes += why + list(getattr(session, "notes", ()))
    filed: dict[str, list[CaseResult]] = defaultdict(list)
    for case in cases:
        found = judges[case.id][2]
        elsewhere = [r for r in found if r.filed_under is not None]
        checks = [r for r in found if r.filed_under is None] if elsewhere else found
        if case.id not in timelines and len(checks) > 1:
            checks = sorted(checks, key=_check_name)
        data = case.data
        passive = findings_elsewhere(elsewhere, groups) if elsewhere else {}
        covered = case.id in waivers.by_id and any(failing(worst({r.verdict for r in found}), True)
                                                   for found in passive.values())
        verdict, waiver = _waived(case.id, data, edition, checks, waivers, covered)
        explained = (suite.implementation_errata(case.id, errata, case.data.get("tags", ()))
                     if failing(verdict, strict=False) else [])
        filed[case.group].append(CaseResult(case.id, case.group, verdict, expectation(data, edition),
                                            data["clause"], checks, data.get("rule"), explained,
                                            waiver.reason if waiver else None, timelines.get(case.id, [])))
        for group, found in passive.items():
            filed[group].append(finding(passive_id(name, group, case.id), group, found, waivers))
    messages = [MessageResult(g.name, g.key, message_verdict(filed[g.name], strict), filed[g.name])
                for g in suite.groups if g.name in filed]
    data = {case.id: case.data for case in cases}
    read = {case.id: getattr(kinds[case.kind], "differences_in", None) for case in cases}

    def differences(c: CaseResult) -> list:
        found = read.get(c.id)
        return [d for k in c.checks if k.verdict is Verdict.FAIL for d in found(data[c.id], edition, k)] if found else []

    causes = group_causes((c for m in messages for c in m.cases), lambda c: cause_of(c, data.get(c.id)),
                          describe=lambda key, title, members: described(key, title, members, data, differences))
    stale = []
    if complete and not stopped_at:
        unused = waivers.stale() if shard is None or selection is None else \
            unused_naming(waivers, admitted(suite, selection, hello["kinds"], options)[0], edition)
        stale = [w.selector for w in unused]
    notes += [stale_note(s, shard) for s in stale]
    return RunResult(suite.name, suite.title, edition, hello["implementation"], adapter, strict, started,
                     round(clock() - began, 3), messages, session.stderr, notes, complete and not stopped_at,
                     list(session.incidents), untested, causes=causes,
                     provenance=replace(provenance, errata=errata) if provenance is not None else None,
                     stale_waivers=stale,
                     stopped=complete and bool(stopped_at), shard=shard)


def case_verdict(checks: list[CheckResult], waiver: Waiver | None) -> Verdict:
    """A case's verdict: its checks' worst, or what a waiver makes of it."""
    verdict = checks[0].verdict if len(checks) == 1 else worst({r.verdict for r in checks})
    if waiver is not None:
        verdict = Verdict.WAIVED if failing(verdict, strict=True) else Verdict.WAIVER_STALE
    return verdict


def _waived(case_id: str, data: dict, edition: str, checks: list[CheckResult], waivers: Waivers,
            covered: bool = False) -> tuple[Verdict, Waiver | None]:
    """A case's verdict and the waiver that applies to it: its id's, or the first glob, rule or cause waiver naming
    it that covers its failure (the cause its checks give, as the report groups it); never for an ADAPTER_ERROR.
    ``covered``: its id waiver covers a failing finding it filed under another group (so it is not stale if the case
    itself passes)."""
    verdict = case_verdict(checks, None)
    if not waivers or not waivable(verdict):
        return verdict, None
    unwaived = CaseResult(case_id, "", verdict, expectation(data, edition), "", checks, data.get("rule"))
    cause = cause_of(unwaived, data) if failing(verdict, strict=True) else None
    waiver = waivers.find(case_id, data.get("rule"), about(unwaived, data)[0], cause and cause[0])
    if waiver is None or (covered and cause is None):
        return verdict, None
    return case_verdict(checks, waiver), waiver


def unused_naming(waivers: Waivers, cases: list[Case], edition: str) -> list[Waiver]:
    """The broad waivers naming any of ``cases`` (a shard's whole selection) that waived nothing in this run."""
    named = set()
    for c in cases:
        plain = CaseResult(c.id, c.group, Verdict.PASS, expectation(c.data, edition), "", [], c.data.get("rule"))
        named.update(waivers.naming(c.id, c.data.get("rule"), about(plain, c.data)[0]))
    return [w for w in waivers.broad if w in named and w not in waivers.used]


def finding(case_id: str, group: str, checks: list[CheckResult], waivers: Waivers) -> CaseResult:
    """What a case found about another group, as a case of that group: WAIVED when failing and a waiver covers it
    (the id waiver of the case that made it, a glob matching its id, its cause)."""
    verdict = worst({r.verdict for r in checks})
    out = CaseResult(case_id, group, verdict, None, checks[0].clause or "", checks)
    if waivers and failing(verdict, strict=True) and waivable(verdict):
        waiver = waivers.find(case_id, None, about(out)[0], cause_of(out)[0])
        if waiver is not None:
            out.verdict, out.waiver = Verdict.WAIVED, waiver.reason
    return out


def _fails(suite: str, case_id: str, data: dict, edition: str, found: list[CheckResult], waivers: Waivers,
           strict: bool) -> bool:
    """Whether a case that is done fails: by its own checks (as its waiver has them), or by a finding it filed under
    another group (a case of its own in the result, as its waiver has it)."""
    own, elsewhere = [], defaultdict(list)
    for r in found:
        (own if r.filed_under is None else elsewhere[r.filed_under]).append(r)
    return (bool(own) and failing(_waived(case_id, data, edition, own, waivers)[0], strict)) or any(
        failing(finding(passive_id(suite, group, case_id), group, checks, waivers).verdict, strict)
        for group, checks in elsewhere.items())


def _check_name(result: CheckResult) -> str:
    return result.check


def admitted(suite: Suite, cases: list[Case], kinds: list[str], options: dict) -> tuple[list[Case], list[str]]:
    """The cases to run: those of the kinds the session runs that their kind admits; and notes on the rest."""
    out, declined, other = [], defaultdict(list), Counter()
    admits = {kind: getattr(suite.kinds[kind], "admit", None) for kind in kinds if kind in suite.kinds}
    for case in cases:
        if case.kind not in admits:
            other[case.kind] += 1
            continue
        admit = admits[case.kind]
        reason = admit(case.data, options) if admit is not None else None
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
