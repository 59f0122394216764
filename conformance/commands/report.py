"""``imc-conformance report``: re-render a saved JSON result (any format version this one reads)."""

from __future__ import annotations

from pathlib import Path

from ..errors import UsageError
from .options import add_reports


def add(sub) -> None:
    rep = sub.add_parser("report", help="re-render a saved JSON result")
    rep.add_argument("result", help="a file written by run --json")
    add_reports(rep)
    rep.set_defaults(func=command)


def command(args) -> int:
    from ..files import read_result
    from ..render.terminal import print_result
    from .output import report_targets, terminal, write_reports

    targets = report_targets(args)
    try:
        result = read_result(Path(args.result))
    except ValueError as exc:  # not JSON, unreadable, or not a valid result
        raise UsageError(f"cannot read the result {exc}") from exc
    console = terminal()
    print_result(result, console)
    return 2 if write_reports(result, targets, console) else result.exit_code()
