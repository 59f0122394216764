"""``imc-conformance mutants``: the suite's power as a number. Each seeded-bug implementation of the suite runs
through the corpus and, if the corpus misses it, through the fuzzer with a fixed seed and budget; the command prints
what caught each one and the score caught/total, and fails if a bug survives or an equivalent mutant is caught."""

from __future__ import annotations

from ..arguments import count
from .options import add_suite

DEFAULT_BUDGET = 40


def add(sub) -> None:
    mutants = sub.add_parser("mutants", help="measure the suite's power: which seeded bugs the corpus and the fuzzer catch")
    add_suite(mutants)
    mutants.add_argument("--edition", help="the edition to judge in (default: the suite's first)")
    mutants.add_argument("--mutant", action="append", default=[], metavar="NAME", help="only this mutant (repeatable)")
    mutants.add_argument("--seed", type=count, default=0, metavar="N", help="the fuzzer's seed (default 0)")
    mutants.add_argument("--budget", type=count, default=DEFAULT_BUDGET, metavar="N",
                         help=f"fuzz examples per message and property for a mutant the corpus misses "
                              f"(default {DEFAULT_BUDGET})")
    mutants.set_defaults(func=command)


def command(args) -> int:
    from ..errors import UsageError
    from ..escaping import printable
    from ..files import open_corpus
    from ..fuzz.mutation import score
    from ..arguments import chosen_edition

    suite, cases = open_corpus(args.suite, None, None)
    edition = chosen_edition(suite, args.edition)
    every = suite.mutants(edition)
    if not every:
        raise UsageError(f"the suite {suite.name!r} has no mutants")
    unknown = set(args.mutant) - {m.name for m in every}
    if unknown:
        raise UsageError(f"unknown mutant(s): {', '.join(sorted(unknown))} (mutants: {', '.join(m.name for m in every)})")
    chosen = [m for m in every if not args.mutant or m.name in args.mutant]
    vectors = [c for c in cases if c.kind == "vector"]
    source = suite.fuzz_source(edition, cases)
    outcomes = []
    for mutant in chosen:
        outcome = score(suite, mutant, vectors, edition, source, seed=args.seed, budget=args.budget)
        outcomes.append(outcome)
        if outcome.caught_by is not None:
            where = (f"corpus ({outcome.corpus_cases} cases), first {outcome.caught_by}" if outcome.how == "corpus"
                     else f"fuzz, after the corpus missed it: {outcome.caught_by} ({outcome.judged} examples)")
            status = "CAUGHT" if not mutant.equivalent else "WRONGLY CAUGHT (equivalent)"
        else:
            where = (f"survived the corpus and {outcome.judged} fuzz examples"
                     + (f"; equivalent: {mutant.equivalent}" if mutant.equivalent else ""))
            status = "EQUIVALENT" if mutant.equivalent else "SURVIVED"
        print(f"{status:11} {'new ' if mutant.new else '    '}{printable(mutant.name):34} {printable(where)}")
    bugs = [o for o in outcomes if not o.mutant.equivalent]
    caught = sum(1 for o in bugs if o.caught_by is not None)
    by_fuzz = sum(1 for o in bugs if o.how == "fuzz")
    wrong = [o for o in outcomes if not o.right]
    print(f"score {caught}/{len(bugs)} mutants caught ({by_fuzz} only by the fuzzer, seed {args.seed}, budget "
          f"{args.budget}); {len(outcomes) - len(bugs)} equivalent, surviving as they must" if not [
              o for o in outcomes if o.mutant.equivalent and o.caught_by] else
          f"score {caught}/{len(bugs)}; an equivalent mutant was caught: a verdict fails a conforming choice")
    return 1 if wrong else 0
