"""``imc-conformance report``: re-render a saved JSON result (any format version this one reads)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from ..errors import UsageError
from .options import add_reports


def add(sub) -> None:
    rep = sub.add_parser("report", help="re-render a saved JSON result, or merge the results of a run's shards")
    rep.add_argument("result", nargs="+", help="a file written by run --json (with --merge: one per shard)")
    rep.add_argument("--merge", action="store_true", help="join the results of every shard of one run (run --shard)")
    rep.add_argument("--causes", action="store_true",
                     help="print only the failures grouped by cause, largest first, each with all its cases")
    add_reports(rep)
    rep.set_defaults(func=command)


def command(args) -> int:
    from ..files import read_result
    from ..render.terminal import print_causes, print_result
    from .output import report_targets, terminal, write_reports

    targets = report_targets(args)
    if len(args.result) > 1 and not args.merge:
        raise UsageError("give one result to re-render, or --merge and the results of every shard of a run")
    results = []
    for path in args.result:
        try:
            results.append(read_result(Path(path)))
        except ValueError as exc:  # not JSON, unreadable, or not a valid result
            raise UsageError(f"cannot read the result {exc}") from exc
    result = merged(results, args) if args.merge else results[0]
    console = terminal()
    if args.causes:
        print_causes(result, console, limit=None)
        if not result.cause_groups():
            console.print("no failing or non-strict case: nothing to group")
    else:
        print_result(result, console)
    return 2 if write_reports(result, targets, console) else result.exit_code()


def merged(results, args):
    """The shards' results as one: in the suite's order of messages and of cases (what the whole run gives), made
    by this command line."""
    from ..core.shards import merge
    from ..files import open_corpus

    groups = frozenset(m.name for r in results for m in r.messages)
    try:
        suite, cases = open_corpus(results[0].suite, None, groups)
        result = merge(results, [g.name for g in suite.groups], {c.id: i for i, c in enumerate(cases)})
    except (ValueError, LookupError) as exc:
        raise UsageError(f"cannot merge: {exc}") from exc
    result.provenance = replace(result.provenance, command=list(args.command_line))
    return result
