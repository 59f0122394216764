"""Where a command's results go: the terminal (rich, imported when something is printed) and the report files."""

from __future__ import annotations

import sys
from pathlib import Path

from ..errors import UsageError
from ..escaping import printable
from .options import REPORTS


def terminal():
    """A rich console that interprets nothing it is given (no emoji codes, no highlighting; markup is escaped by
    the renderer); CI logs (not a terminal) get a wide table instead of rich's 80 columns."""
    from rich.console import Console

    return Console(highlight=False, emoji=False, width=None if sys.stdout.isatty() else 160)


def report_targets(args) -> dict[str, Path]:
    """The requested reports by format; two formats to one file is a usage error."""
    targets = {fmt: Path(getattr(args, fmt)) for fmt in REPORTS if getattr(args, fmt)}
    seen: dict[Path, str] = {}
    for fmt, path in targets.items():
        key = path.resolve()
        if key in seen:
            raise UsageError(f"--{seen[key]} and --{fmt} write to the same file {path}")
        seen[key] = fmt
    return targets


def write_reports(result, targets: dict[str, Path], console) -> int:
    """Write each requested report and say where; a report that cannot be written is reported and skipped.
    Returns the number of reports that could not be written."""
    if not targets:
        return 0
    from ..render import RENDERERS

    return sum(write_file(path, RENDERERS[fmt](result), f"{fmt} report", console) for fmt, path in targets.items())


def write_file(path: Path, text: str, what: str, console) -> int:
    """Write ``text`` to ``path`` (creating its folder) and say so; 1 after a one-line error if that fails."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
    except OSError as exc:
        print(f"imc-conformance: cannot write the {what} to {printable(str(path))}: {exc.strerror or exc}",
              file=sys.stderr)
        return 1
    console.print(f"{what}: {printable(str(path))}", highlight=False, markup=False)
    return 0


def finish(result, targets: dict[str, Path], damage: list[str], complete: bool) -> int:
    """Show a judged capture or log, write its reports, say what of it could not be read (one line each); the exit
    code: 2 where a report could not be written or the input is damaged (what was before the damage is judged)."""
    from ..render.terminal import print_result

    console = terminal()
    print_result(result, console)
    problems = write_reports(result, targets, console)
    for line in damage:
        print(f"imc-conformance: {printable(line)}", file=sys.stderr)
    if not complete:
        return result.exit_code()
    say_untested(result)
    return 2 if problems or damage else result.exit_code()


def say_untested(result) -> None:
    """The one line (on stderr) of a result in which nothing could be tested, why, and that it exits 2."""
    line = result.nothing_tested()
    if line is not None:
        print(f"imc-conformance: {printable(line)}; exit 2", file=sys.stderr)
