"""The implementation matrix: saved results of any suite and kind side by side, implementations × messages (or ×
cases), as Markdown and as a self-contained HTML page.

Results are grouped by (suite, edition): a table never mixes suites or editions. Within one table, a result whose
selection of cases differs from the others' in a message is labelled in that cell (``≠``, with the count), so that a
shorter run is never read as a cleaner one.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field

from ..core.results import RunResult

@dataclass
class Column:
    """One saved result: who was judged, and how the run went."""

    name: str
    implementation: str
    kind: str  # what the result holds: vectors, scenarios, captures, fuzzing (from its case ids)
    overall: str
    duration: float


@dataclass
class Cell:
    verdict: str
    counts: str  # e.g. "120 PASS · 2 FAIL"
    differs: str = ""  # why this cell's selection differs from its row's other cells
    errata: str = ""  # the documented errata that explain its failures


@dataclass
class Table:
    suite: str
    title: str
    edition: str
    columns: list[Column]
    rows: list[tuple[str, list[Cell | None]]] = field(default_factory=list)


def kind_of(result: RunResult) -> str:
    """What a saved result holds: a capture's judgement, a fuzzing run, scenarios or byte vectors."""
    ids = [c.id for c in result.cases]
    if result.adapter == "capture":
        return "captures"
    if ids and all("/fuzz/" in i for i in ids):
        return "fuzzing"
    if any("/scenario/" in i or "/passive/" in i for i in ids):
        return "scenarios"
    return "vectors"


def build(results: list[tuple[str, RunResult]], by_case: bool) -> list[Table]:
    """``results``: (label, result) pairs. One table per (suite, edition), rows by message (or case)."""
    tables: dict[tuple[str, str], Table] = {}
    for label, r in results:
        key = (r.suite, r.edition)
        table = tables.get(key) or tables.setdefault(key, Table(r.suite, r.title, r.edition, []))
        table.columns.append(Column(label, r.implementation, kind_of(r), r.overall(), r.duration))
    for (suite, edition), table in tables.items():
        members = [r for _, r in results if (r.suite, r.edition) == (suite, edition)]
        if by_case:
            names = list(dict.fromkeys(c.id for r in members for c in r.cases))
            found = [{c.id: c for c in r.cases} for r in members]
            table.rows = [(n, [Cell(f[n].verdict.value, "") if n in f else None for f in found]) for n in names]
            continue
        names = list(dict.fromkeys(m.name for r in members for m in r.messages))
        found = [{m.name: m for m in r.messages} for r in members]
        for name in names:
            selections = [frozenset(c.id for c in f[name].cases) if name in f else None for f in found]
            common = Counter(s for s in selections if s is not None).most_common(1)[0][0]
            cells = []
            for f, chosen in zip(found, selections):
                if chosen is None:
                    cells.append(None)
                    continue
                m = f[name]
                counts = Counter(c.verdict for c in m.cases)
                text = " · ".join(f"{n} {v.value}" for v, n in sorted(counts.items(), key=lambda x: x[0].value))
                differs = "" if chosen == common else f"{len(chosen)} cases, not the {len(common)} of the others"
                errata = ", ".join(sorted({e for c in m.cases for e in c.errata}))
                cells.append(Cell(m.verdict, text, differs, errata))
            table.rows.append((name, cells))
    return list(tables.values())


def render_markdown(tables: list[Table], by_case: bool) -> str:
    from .markdown import cell

    lines = ["# Implementation matrix", ""]
    for t in tables:
        lines += [f"## {cell(t.title)} — edition {cell(t.edition)}", ""]
        lines += ["| implementation | judged | result | seconds |", "|---|---|---|---:|"]
        lines += [f"| {cell(c.name)} | {cell(c.implementation)} ({cell(c.kind)}) | {cell(c.overall)} | {c.duration:.2f} |"
                  for c in t.columns]
        lines += ["", "| " + ("case" if by_case else "message") + " | " + " | ".join(cell(c.name) for c in t.columns) + " |",
                  "|---|" + "---|" * len(t.columns)]
        for name, cells in t.rows:
            shown = []
            for c in cells:
                if c is None:
                    shown.append("—")
                else:
                    text = f"**{c.verdict}**" + (f" ({cell(c.counts)})" if c.counts else "")
                    text += f" errata {cell(c.errata)}" if c.errata else ""
                    shown.append(text + (f" ≠ {cell(c.differs)}" if c.differs else ""))
            lines.append(f"| {cell(name)} | " + " | ".join(shown) + " |")
        lines.append("")
    lines.append("≠: this result judged another selection of the message's cases than most results in its table.")
    return "\n".join(lines) + "\n"


def render_html(tables: list[Table], by_case: bool) -> str:
    from .html import environment

    return environment().get_template("matrix.html.j2").render(tables=tables, by_case=by_case)
