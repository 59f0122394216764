"""``imc-conformance list``: the selected cases, one per line (id, expectation, clause), or the live ones with
what they need."""

from __future__ import annotations

from ..errors import UsageError
from .options import add_selection


def add(sub) -> None:
    lst = sub.add_parser("list", help="list the selected cases (id, expectation, clause)")
    add_selection(lst)
    lst.add_argument("--scenarios", action="store_true",
                     help="only scenarios, with what they need (--param), their effects and service")
    lst.set_defaults(func=command)


def command(args) -> int:
    from ..core.cases import expectation
    from .run import selection

    suite, _, cases, _ = selection(args)
    if args.scenarios:
        from ..live import list_live_cases
        try:
            return list_live_cases(suite, cases)
        except ValueError as exc:
            raise UsageError(str(exc)) from exc
    edition = args.edition
    print("".join(f"{case.id}\t{expectation(case.data, edition)}\t{case.data['clause']}\n" for case in cases), end="")
    return 0
