"""The suite's power as a number: seeded-bug implementations (a suite's mutants) run through the corpus, and those the
corpus misses through the fuzzer's search with a fixed budget. A mutant is caught by the first case that fails it
(FAIL, CRASH, TIMEOUT, ADAPTER_ERROR, or NON_STRICT where the bug only changes the rule a refusal names); an
equivalent mutant (a choice the seeds permit) must survive both, with its reason stated."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from ..core.runner import run_cases
from ..core.verdicts import Verdict, failing
from ..sessions.library import LibrarySession
from .engine import Search


@dataclass(frozen=True)
class Mutant:
    """One seeded bug: ``make()`` builds the implementation (a library adapter); ``equivalent`` says why a mutant
    is conforming after all (it must then survive)."""

    name: str
    bug: str
    make: Callable[[], object]
    equivalent: str | None = None
    new: bool = False  # added with the fuzzer (the issue asked for new mutants beyond the first set)


@dataclass
class Outcome:
    mutant: Mutant
    caught_by: str | None  # the case or generated example that caught it
    how: str | None  # "corpus" or "fuzz"
    corpus_cases: int  # corpus cases that fail it
    judged: int = 0  # fuzz examples judged (when the corpus missed it)

    @property
    def right(self) -> bool:
        """Caught if it is a bug, surviving if it is equivalent."""
        return (self.caught_by is None) == bool(self.mutant.equivalent)


def catches(verdict: Verdict) -> bool:
    return failing(verdict, strict=False) or verdict == Verdict.NON_STRICT


def score(suite, mutant: Mutant, cases: list, edition: str, source, *, seed: int, budget: int) -> Outcome:
    """Run one mutant over ``cases``, then (if it survives them) through the search."""
    session = LibrarySession(mutant.make(), mutant.name)
    result = run_cases(session, suite, cases, edition=edition, adapter=mutant.name)
    caught = [c.id for c in result.cases if catches(c.verdict)]
    if caught:
        return Outcome(mutant, caught[0], "corpus", len(caught))
    search = Search(suite, source, {mutant.name: session}, edition, seed=seed, budget=budget, max_findings=1,
                    first_only=True)
    tally = search.run(source.groups)
    judged = sum(tally.judged.values())
    if tally.findings:
        return Outcome(mutant, tally.findings[0].case["id"], "fuzz", 0, judged)
    return Outcome(mutant, None, None, 0, judged)
