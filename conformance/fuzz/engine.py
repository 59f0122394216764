"""The search: hypothesis draws inputs from a suite's source, each becomes a vector case whose expectation is the
reference's, and the one runner judges it through every session. A failing verdict whose signature (which
implementations fail which check, how, and with which errata) has not been seen is a finding; hypothesis then
shrinks it to its smallest input, and the search goes on for other signatures until the budget is spent. A finding
that the documented errata of every deviating implementation explain is reported as first seen, unshrunk: it is
known, and shrinking it would spend the time the unknown ones need.

Reproducible: hypothesis runs with a ``random.Random`` seeded from ``(seed, suite, group, property, round)``, no
deadline and no example database (a seeded search keeps none), so the same seed and budget give the same findings.
"""

from __future__ import annotations

import random
import time
from collections import Counter
from contextlib import contextmanager
from dataclasses import dataclass, field

from ..core.cases import Case, expectation
from ..core.results import CaseResult
from ..core.runner import run_cases
from ..core.verdicts import UNTESTED, failing
from .source import PROPERTIES

MAX_FINDINGS = 4  # distinct findings per group and property
SWEEP_BATCH = 2000  # mutated frames the sweep builds and judges at a time


@contextmanager
def reproducible():
    """Hypothesis also draws constants it finds in the modules loaded from outside site-packages ("local constants"):
    which modules a process has loaded (an editable install, a test suite) would then change the findings of a seed.
    Switched off while a search runs. This reaches into hypothesis's internals, which is why pyproject.toml pins
    hypothesis exactly and tests/test_fuzz.py checks the result across processes."""
    from hypothesis.internal.conjecture import providers

    saved = providers._get_local_constants
    empty = providers.Constants(integers=providers.SortedSet(), floats=providers.SortedSet(key=providers.float_to_int),
                                bytes=providers.SortedSet(), strings=providers.SortedSet())
    providers.CONSTANTS_CACHE.cache.clear()
    providers._get_local_constants = lambda: empty
    try:
        yield
    finally:
        providers._get_local_constants = saved
        providers.CONSTANTS_CACHE.cache.clear()


class OutOfTime(Exception):
    """The search's duration is spent (``--duration``)."""


@dataclass
class Finding:
    """A shrunk input on which some implementation deviates from the reference: its case, each implementation's
    result on it, and how the deviation splits the implementations."""

    group: str
    prop: str
    case: dict
    results: dict[str, CaseResult]
    classification: str

    @property
    def deviating(self) -> list[str]:
        return [name for name, r in self.results.items() if failing(r.verdict, strict=False)]

    @property
    def unexplained(self) -> list[str]:
        """The implementations whose failure no documented erratum explains."""
        return [name for name in self.deviating if not self.results[name].errata]


@dataclass
class Tally:
    """Examples judged per (group, property), and the findings."""

    judged: dict[tuple[str, str], int] = field(default_factory=dict)
    # per (group, property): the examples sent to every implementation (shrinking's included), and per implementation
    # those it answered only UNSUPPORTED or INCONCLUSIVE (untested)
    sent: Counter = field(default_factory=Counter)
    untested: dict[tuple[str, str], Counter] = field(default_factory=dict)
    findings: list[Finding] = field(default_factory=list)
    stopped: str | None = None  # why the search ended early, if it did


def seed_frames(source, group: str) -> list[tuple[str, bytes]]:
    """The group's corpus frames, shortest first (the order shrinking tries them in)."""
    return sorted(source.seed_frames(group), key=lambda ef: (len(ef[1]), ef))


def mutated_cases(source, group: str, rng: random.Random, count: int) -> dict[str, tuple[dict, tuple]]:
    """``count`` mutations of the group's corpus frames drawn from ``rng`` (no hypothesis), as cases by id (each
    once) with the mutation and choices that made them; frames the reference does not judge are left out."""
    seeds = seed_frames(source, group)
    out: dict[str, tuple[dict, tuple]] = {}
    for _ in range(count if seeds else 0):
        encoding, frame = rng.choice(seeds)
        mutation, a, b = rng.choice(source.mutations), rng.randrange(1 << 16), rng.randrange(1 << 16)
        case = source.frame_case(group, encoding, source.mutate(group, frame, encoding, mutation, a, b), mutation)
        if case is not None:
            out.setdefault(case["id"], (case, (mutation, a, b)))
    return out


def _size(case: dict) -> int:
    return min(len(h) for h in case["frames"].values())


def classify(names: list[str], results: dict) -> str:
    """How a deviation splits the implementations (``results``: each one's CaseResult)."""
    deviating = [n for n in names if failing(results[n].verdict, strict=False)]
    if len(names) == 1:
        return f"{names[0]} deviates from the reference"
    if set(deviating) == set(names):
        if all(results[n].errata for n in names):
            return "every implementation deviates from the reference, each as a documented erratum says"
        return "every implementation deviates from the reference: review the reference and the definitions"
    agree = [n for n in names if n not in deviating]
    return f"{', '.join(deviating)} {'deviates' if len(deviating) == 1 else 'deviate'}; {', '.join(agree)} " \
           f"{'matches' if len(agree) == 1 else 'match'} the reference"


class Search:
    """One fuzzing run of a suite's source against named sessions."""

    def __init__(self, suite, source, sessions: dict, edition: str, *, seed: int, budget: int,
                 until: float | None = None, max_findings: int = MAX_FINDINGS, first_only: bool = False):
        self.suite, self.source, self.sessions, self.edition = suite, source, sessions, edition
        self.seed, self.budget, self.until = seed, budget, until
        self.max_findings, self.first_only = max_findings, first_only
        self.tally = Tally()
        self._key = ("", "")  # the (group, property) being searched: what the untested answers are counted under

    def judge(self, case: dict) -> dict[str, CaseResult]:
        """Every session's result on one case, through the runner (the corpus's own verdict policy and errata)."""
        return self.judge_all([case])[case["id"]]

    def judge_all(self, cases: list[dict]) -> dict[str, dict[str, CaseResult]]:
        """Every session's result on each case (by case id), each session running the cases as one batch."""
        batch = [Case(c["id"], c["id"].split("/")[1], "vector", c) for c in cases]
        out: dict[str, dict[str, CaseResult]] = {}
        untested = self.tally.untested.setdefault(self._key, Counter())
        self.tally.sent[self._key] += len(cases)
        for name, session in self.sessions.items():
            for r in run_cases(session, self.suite, batch, edition=self.edition, adapter=name, evidence=False).cases:
                out.setdefault(r.id, {})[name] = r
                untested[name] += r.verdict in UNTESTED
        for case in cases:
            self.suite.kinds["vector"].forget(case, self.edition)
        return out

    def signature(self, case: dict, results: dict[str, CaseResult]):
        deviating = [(name, r.verdict.value, next((c.check.split("-")[0] for c in r.checks
                                                    if failing(c.verdict, strict=False)), ""),
                      tuple(r.errata)) for name, r in results.items() if failing(r.verdict, strict=False)]
        if not deviating:
            return None
        return expectation(case, self.edition), case.get("rule"), tuple(deviating)

    def run(self, groups, props=PROPERTIES) -> Tally:
        for group in groups:
            for prop in props:
                try:
                    self.search(group, prop)
                except OutOfTime:
                    self.tally.stopped = "the duration was spent"
                    return self.tally
                if self.first_only and self.tally.findings:
                    return self.tally
        return self.tally

    def sweep(self, groups, per_group: int) -> None:
        """The fast engine: ``per_group`` mutations of the group's corpus frames drawn with a seeded ``random.Random``
        (no hypothesis), judged in batches of ``SWEEP_BATCH`` (memory stays bounded; the duration is checked between
        batches). Each new deviation is shrunk by hand: the same mutation is tried on the group's shorter corpus
        frames, shortest first, and with smaller choices, and the first that still deviates the same way is the
        finding."""
        rng = random.Random(f"{self.seed}/{self.suite.name}/sweep")
        for group in groups:
            seeds = seed_frames(self.source, group)
            if not seeds:
                continue
            drawn: set[str] = set()  # case ids judged: a mutation drawn again is judged once
            seen: set = set()
            self.tally.judged[(group, "sweep")] = 0
            self._key = (group, "sweep")
            for start in range(0, per_group, SWEEP_BATCH):
                if self.until is not None and time.monotonic() > self.until:
                    self.tally.stopped = "the duration was spent"
                    return
                batch = mutated_cases(self.source, group, rng, min(SWEEP_BATCH, per_group - start))
                cases = {i: c for i, c in batch.items() if i not in drawn}
                drawn.update(cases)
                self.tally.judged[(group, "sweep")] += len(cases)
                results = self.judge_all([c for c, _ in cases.values()])
                for case_id, (case, how) in cases.items():
                    sig = self.signature(case, results[case_id])
                    if sig is None or sig in seen:
                        continue
                    seen.add(sig)
                    case, found = self.smallest(group, seeds, how, sig, case, results[case_id])
                    self.tally.findings.append(Finding(case["id"].split("/")[1], "sweep", case, found,
                                                       classify(list(self.sessions), found)))

    def smallest(self, group, seeds, how, sig, case, results):
        """The shortest input deviating as ``sig`` does: the same mutation on shorter frames, then smaller choices
        (every candidate judged in one batch, the first in that order that deviates the same way kept)."""
        mutation, a, b = how
        candidates: dict[str, dict] = {}
        for encoding, frame in seeds:
            for a_, b_ in ((0, 0), (a % 64, b % 64), (a, b)):
                candidate = self.source.frame_case(group, encoding, self.source.mutate(group, frame, encoding, mutation,
                                                                                        a_, b_), mutation)
                if candidate is not None and _size(candidate) <= _size(case):
                    candidates.setdefault(candidate["id"], candidate)
        judged = self.judge_all(list(candidates.values()))
        for candidate in candidates.values():
            if self.signature(candidate, judged[candidate["id"]]) == sig:
                return candidate, judged[candidate["id"]]
        return case, results

    def search(self, group: str, prop: str) -> None:
        from hypothesis import HealthCheck, Phase, Verbosity, find, settings
        from hypothesis.errors import NoSuchExample, Unsatisfiable

        key = self._key = (group, prop)
        self.tally.judged[key] = 0
        seen: set = set()
        strategy = self.source.inputs(group, prop).map(lambda drawn: self.source.case(group, prop, drawn))

        def condition(case) -> bool:
            if self.until is not None and time.monotonic() > self.until:
                raise OutOfTime
            if case is None:
                return False
            self.tally.judged[key] += 1
            results = self.judge(case)
            sig = self.signature(case, results)
            if sig is None or sig in seen:
                return False
            if all(results[n].errata for n in results if failing(results[n].verdict, strict=False)):
                # a documented erratum: reported as first seen, not shrunk, and no round of the search spent on it
                seen.add(sig)
                self.tally.findings.append(Finding(case["id"].split("/")[1], prop, case, results,
                                                   classify(list(self.sessions), results)))
                return False
            return True

        for round_ in range(self.max_findings):
            left = self.budget - self.tally.judged[key]
            if left <= 0:
                return
            config = settings(max_examples=left, deadline=None, database=None, phases=[Phase.generate, Phase.shrink],
                              suppress_health_check=list(HealthCheck), verbosity=Verbosity.quiet,
                              report_multiple_bugs=False)
            rng = random.Random(f"{self.seed}/{self.suite.name}/{group}/{prop}/{round_}")
            try:
                with reproducible():
                    case = find(strategy, condition, settings=config, random=rng)
            except (NoSuchExample, Unsatisfiable):
                return
            results = self.judge(case)
            sig = self.signature(case, results)
            if sig is None or sig in seen:  # cannot happen for a deterministic implementation; never loop on it
                return
            seen.add(sig)
            case, results = self.reduced(group, prop, case, results, sig)
            self.tally.findings.append(Finding(case["id"].split("/")[1], prop, case, results,
                                               classify(list(self.sessions), results)))

    def reduced(self, group: str, prop: str, case: dict, results: dict, sig):
        """The shrunk finding reduced to the one property it deviates on: what the source calls incidental in it (an
        IMC header shrunk to zeros) made ordinary, kept if the implementations still deviate the same way."""
        ordinary = getattr(self.source, "ordinary", None)
        candidate = ordinary(group, prop, case) if ordinary else None
        if candidate is None or candidate["id"] == case["id"]:
            return case, results
        judged = self.judge(candidate)
        found = self.signature(candidate, judged)  # the same deviation (what made the case acceptable may be gone)
        return (candidate, judged) if found is not None and found[1:] == sig[1:] else (case, results)
