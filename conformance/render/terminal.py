"""The terminal rendering of a run: a table per message, the failing cases, incidents, notes, the summary (rich).

Every piece of text from the result passes ``printable`` (control characters shown as escapes) and rich's
``escape`` (no markup), and the console interprets no emoji codes (``cli.terminal``), so an implementation can
neither drive the terminal nor forge lines in a CI log.
"""

from __future__ import annotations

from rich.console import Console
from rich.markup import escape
from rich.table import Table

from ..core.results import RunResult
from ..core.verdicts import Verdict, failing
from ..escaping import printable
from ..core.wording import counted
from .common import cause_line, incident_lines, provenance_lines, timeline_lines, waived

COLUMNS = (Verdict.PASS, Verdict.FAIL, Verdict.NON_STRICT, Verdict.IMPL_DEFINED, Verdict.WAIVED)
SHOWN_FAILURES = 20
SHOWN_TIMELINE = 12  # timeline entries under a failing scenario
SHOWN_CAUSES = 20


def print_causes(result: RunResult, console: Console, limit: int | None = SHOWN_CAUSES) -> None:
    """The failures grouped by cause, largest first (``limit`` groups; None: all, each with every case id)."""
    causes = result.cause_groups()
    if not causes:
        return
    console.print(f"[bold]Causes[/]: {sum(len(c.cases) for c in causes)} failing or non-strict cases, "
                  f"{len(causes)} cause{'s' if len(causes) != 1 else ''}, largest first")
    for n, cause in enumerate(causes[:limit], 1):
        console.print(f"{n:3}. {safe(cause_line(cause))}")
        if limit is None:
            for case_id in cause.cases:
                console.print(f"       {safe(case_id)}")
    if limit is not None and len(causes) > limit:
        console.print(f"… and {len(causes) - limit} more causes (report --causes lists them all)")


def safe(text: str | None) -> str:
    """Result text made inert for a rich console."""
    return escape(printable(text))


def print_result(result: RunResult, console: Console) -> None:
    print_causes(result, console)
    title = f"{result.implementation} — {result.title} corpus, edition {result.edition}"
    table = Table(title=safe(title + ("" if result.complete else " (INCOMPLETE: stopped at its first failing case)"
                                      if result.stopped else " (INCOMPLETE: interrupted)")))
    table.add_column("message")
    table.add_column("key", justify="right")
    table.add_column("verdict")
    for v in COLUMNS:
        table.add_column(v.value, justify="right")
    table.add_column("other", justify="right")
    table.add_column("known errata")
    for m in result.messages:
        counts = m.counts
        other = sum(n for v, n in counts.items() if v not in COLUMNS)
        errata = sorted({e for c in m.cases for e in c.errata})
        colour = {"PASS": "green", "FAIL": "red", "UNSUPPORTED": "dim"}.get(m.verdict, "yellow")
        table.add_row(safe(m.name), safe(m.key), f"[{colour}]{m.verdict}[/]", *(str(counts[v]) for v in COLUMNS),
                      str(other), safe(", ".join(errata)))
    console.print(table)
    shown = [c for c in result.cases if failing(c.verdict, result.strict)]
    for c in shown[:SHOWN_FAILURES]:
        errata = f" [dim](erratum {safe(', '.join(c.errata))})[/]" if c.errata else ""
        console.print(f"[red]{c.verdict.value}[/] {safe(c.id)}{errata}: {safe(c.detail[:300])}")
        for line in timeline_lines(c, SHOWN_TIMELINE):
            console.print(f"    [dim]{safe(line[:200])}[/]")
    noted: dict[tuple, list[str]] = {}  # not failing, but worth a look: grouped by verdict and detail
    for c in result.cases:
        if c.verdict in (Verdict.NON_STRICT, Verdict.INCONCLUSIVE) and not failing(c.verdict, result.strict):
            noted.setdefault((c.verdict.value, c.detail), []).append(c.id)
    for (verdict, detail), ids in list(noted.items())[:SHOWN_FAILURES]:
        which = safe(ids[0]) if len(ids) == 1 else f"{len(ids)} cases ({safe(', '.join(ids[:3]))}{', …' if len(ids) > 3 else ''})"
        console.print(f"[yellow]{verdict}[/] {which}: {safe(detail[:300])}")
    if len(noted) > SHOWN_FAILURES:
        console.print(f"… and {len(noted) - SHOWN_FAILURES} more groups of non-strict or inconclusive cases")
    if len(shown) > SHOWN_FAILURES:
        console.print(f"… and {len(shown) - SHOWN_FAILURES} more failing cases (see --json/--html reports)")
    reasons = waived(result)
    for reason, ids in reasons[:SHOWN_FAILURES]:
        which = safe(ids[0]) if len(ids) == 1 else f"{len(ids)} cases ({safe(', '.join(ids[:3]))}{', …' if len(ids) > 3 else ''})"
        console.print(f"[dim]WAIVED[/] {which}: waiver: {safe(reason[:300])}")
    if len(reasons) > SHOWN_FAILURES:
        console.print(f"… and {len(reasons) - SHOWN_FAILURES} more waivers' reasons (see --json/--html reports)")
    for line in incident_lines(result):
        console.print(f"[red]incident:[/] {safe(line[:600])}")
    for note in result.notes:
        console.print(f"[yellow]note:[/] {safe(note)}")
    for line in provenance_lines(result):
        console.print(f"[dim]{safe(line[:600])}[/]")
    summary = ", ".join(f"{n} {v}" for v, n in result.summary.items())
    explained = sum(1 for c in shown if c.errata)
    errata = "1 failure is a documented erratum" if explained == 1 else f"{explained} failures are documented errata"
    if result.messages:  # the headline, then the count of cases (the last line)
        colour = {"PASS": "green", "FAIL": "red"}.get(result.overall(), "yellow")
        console.print(f"[bold {colour}]{safe(result.headline())}[/]")
    console.print(f"{counted(len(result.cases), 'case')} in {result.duration:.2f} s" + (f": {summary}" if summary else "")
                  + (f" ({errata})" if explained else ""))
