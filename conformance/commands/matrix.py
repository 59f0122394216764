"""``imc-conformance matrix``: saved results of any suite and kind (vectors, scenarios, captures, fuzzing) side by
side, implementations × messages (or × cases), as Markdown and HTML. Tables never mix suites or editions; a result
that judged another selection of a message's cases is labelled in its cell."""

from __future__ import annotations

from pathlib import Path

from ..errors import UsageError


def add(sub) -> None:
    matrix = sub.add_parser("matrix", help="saved results side by side: implementations × messages")
    matrix.add_argument("results", nargs="+", type=Path, metavar="RESULT.json",
                        help="saved results (run/pcap/fuzz --json), one column each; LABEL=FILE names the column")
    matrix.add_argument("--cases", action="store_true", help="one row per case instead of per message")
    matrix.add_argument("--markdown", metavar="FILE", help="write the Markdown matrix to FILE")
    matrix.add_argument("--html", metavar="FILE", help="write the HTML matrix to FILE")
    matrix.set_defaults(func=command)


def command(args) -> int:
    from ..files import read_result
    from ..render.matrix import build, render_html, render_markdown
    from .output import terminal, write_file

    results, labels = [], set()
    for given in args.results:
        label, sep, path = str(given).partition("=")
        path = Path(path) if sep else given
        try:
            result = read_result(path)
        except ValueError as exc:
            raise UsageError(str(exc)) from exc
        label = unique(label if sep and label else result.adapter, path, labels)
        labels.add(label)
        results.append((label, result))
    tables = build(results, args.cases)
    markdown = render_markdown(tables, args.cases)
    console = terminal()
    problems = 0
    if args.markdown:
        problems += write_file(Path(args.markdown), markdown, "markdown matrix", console)
    if args.html:
        problems += write_file(Path(args.html), render_html(tables, args.cases), "html matrix", console)
    if not args.markdown and not args.html:
        print(markdown, end="")
    return 2 if problems else 0


def unique(label: str, path: Path, taken: set[str]) -> str:
    """``label``, or where another column has it, the label with the file's name, its path, then a number."""
    for candidate in (label, f"{label} ({path.name})", f"{label} ({path})"):
        if candidate not in taken:
            return candidate
    n = 2
    while f"{label} ({path}) {n}" in taken:
        n += 1
    return f"{label} ({path}) {n}"
