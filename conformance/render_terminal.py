"""The terminal rendering of a run: a table per message, the failing cases, the summary (rich)."""

from __future__ import annotations

from rich.console import Console
from rich.markup import escape
from rich.table import Table

from .evaluate import Verdict
from .results import FAILING, RunResult

COLUMNS = (Verdict.PASS, Verdict.FAIL, Verdict.NON_STRICT, Verdict.IMPL_DEFINED, Verdict.WAIVED)
SHOWN_FAILURES = 20


def print_result(result: RunResult, console: Console) -> None:
    table = Table(title=escape(f"{result.implementation} — IMC corpus, edition {result.edition}"))
    table.add_column("message")
    table.add_column("id", justify="right")
    table.add_column("verdict")
    for v in COLUMNS:
        table.add_column(v.value, justify="right")
    table.add_column("other", justify="right")
    table.add_column("known errata")
    for m in result.messages:
        counts = m.counts
        other = sum(n for v, n in counts.items() if v not in COLUMNS)
        errata = sorted({e for c in m.cases for e in c.errata})
        colour = "green" if m.verdict == "PASS" else "red"
        table.add_row(m.name, str(m.id), f"[{colour}]{m.verdict}[/]", *(str(counts[v]) for v in COLUMNS), str(other),
                      ", ".join(errata))
    console.print(table)
    failing = [c for c in result.cases if c.verdict in FAILING or (result.strict and c.verdict is Verdict.NON_STRICT)]
    for c in failing[:SHOWN_FAILURES]:
        errata = f" [dim](erratum {', '.join(c.errata)})[/]" if c.errata else ""
        console.print(f"[red]{c.verdict.value}[/] {escape(c.id)}{errata}: {escape(c.detail[:300])}")
    if len(failing) > SHOWN_FAILURES:
        console.print(f"… and {len(failing) - SHOWN_FAILURES} more failing cases (see --json/--html reports)")
    for note in result.notes:
        console.print(f"[yellow]note:[/] {escape(note)}")
    summary = ", ".join(f"{n} {v}" for v, n in result.summary.items())
    explained = sum(1 for c in failing if c.errata)
    console.print(f"{len(result.cases)} cases in {result.duration:.2f} s: {summary}"
                  + (f" ({explained} failures are documented errata)" if explained else ""))
