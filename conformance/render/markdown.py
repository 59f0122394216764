"""GitHub-flavoured Markdown for pull-request comments and ``$GITHUB_STEP_SUMMARY``."""

from __future__ import annotations

import re

from ..core.verdicts import Verdict
from ..core.results import RunResult
from ..escaping import clean
from ..core.wording import counted
from .common import (TIMELINE_LIMIT, attention, cause_numbers, errata_text, incident_lines, provenance_lines,
                     verdict_columns, waived)

EMOJI = {
    Verdict.PASS: "✅", Verdict.FAIL: "❌", Verdict.NON_STRICT: "⚠️", Verdict.IMPL_DEFINED: "ℹ️",
    Verdict.UNSUPPORTED: "⏭️", Verdict.CRASH: "💥", Verdict.TIMEOUT: "⏱️", Verdict.ADAPTER_ERROR: "🛠️",
    Verdict.WAIVED: "🙈", Verdict.WAIVER_STALE: "🧹", Verdict.INCONCLUSIVE: "❔",
}
OVERALL = {"PASS": "✅", "FAIL": "❌", "ERROR": "🛠️", "INCOMPLETE": "⏸️", "INCONCLUSIVE": "❔", "UNSUPPORTED": "⏭️",
           "WAIVED": "🙈"}
MAX_CASES = 50
MAX_DETAIL = 300
MAX_TIMELINES = 10  # scenarios whose timeline is shown
MAX_CAUSES = 30
MAX_CAUSE_CASES = 50  # case ids listed under a cause

_ENTITIES = {"&": "&amp;", "<": "&lt;", ">": "&gt;", "|": "&#124;", "`": "&#96;", ":": "&#58;"}  # ":x:" is an emoji
_SPECIAL = re.compile(r"[&<>|`:]|[\\*_\[\]~]")


def cell(text: str, limit: int | None = None) -> str:
    """``text`` safe inside a table cell: one line, no table breaks, no HTML, no Markdown emphasis, links or emoji
    codes (GitHub renders ``:skull:``)."""
    text = " ".join(clean(text).split())
    if limit and len(text) > limit:
        text = text[:limit - 1] + "…"
    return _SPECIAL.sub(lambda m: _ENTITIES.get(m[0], "\\" + m[0]), text)


def render_markdown(result: RunResult) -> str:
    verdict = result.overall()
    columns = verdict_columns(result)
    total = len(result.cases)
    lines = [
        f"## {OVERALL[verdict]} {cell(result.title)} conformance: {cell(result.headline())} — {cell(result.implementation)} · "
        f"{cell(result.edition)}",
        "",
        f"**{counted(total, 'case')}** in {counted(len(result.messages), 'message')}: "
        + ", ".join(f"{EMOJI[Verdict(v)]} {n} {v}" for v, n in result.summary.items())
        + f" · adapter {cell(result.adapter)} · {result.duration:.1f} s · {cell(result.started)}"
        + (" · strict" if result.strict else ""),
        "",
        *cause_table(result),
        "| Message | Verdict | " + " | ".join(v.value for v in columns) + " |",
        "|---|---|" + "--:|" * len(columns),
    ]
    for m in result.messages:
        counts = m.counts
        lines.append(f"| {cell(m.name)} ({cell(m.key)}) | {OVERALL.get(m.verdict, '')} {m.verdict} | "
                     + " | ".join(str(counts[v] or "") for v in columns) + " |")
    if not result.complete:
        lines += ["", f"**Incomplete run**: it {'stopped at its first failing case' if result.stopped else 'was interrupted'};"
                  " only the cases done so far are counted."]
    if result.incidents:
        lines += [""] + [f"- ⚠️ {cell(line, 1000)}" for line in incident_lines(result)]
    if result.notes:
        lines += [""] + [f"- {cell(note)}" for note in result.notes]
    lines += ["", "<details><summary>Provenance</summary>", ""] + [f"- {cell(line, 1000)}" for line in
                                                                   provenance_lines(result)] + ["", "</details>"]
    failing = attention(result)
    if failing:
        numbers = cause_numbers(result)
        lines += ["", f"<details><summary>{len(failing)} failing, non-strict or inconclusive cases</summary>", "",
                  "| Case | Verdict | Cause | Detail | Errata |", "|---|---|--:|---|---|"]
        lines += [f"| <code>{cell(c.id)}</code> | {EMOJI[c.verdict]} {c.verdict.value} | {numbers.get(c.id, '')} | "
                  f"{cell(c.detail, MAX_DETAIL)} | {cell(', '.join(c.errata))} |" for c in failing[:MAX_CASES]]
        if len(failing) > MAX_CASES:
            lines += ["", f"and {len(failing) - MAX_CASES} more (see the full report)."]
        lines += ["", "</details>"]
        for c in [c for c in failing if c.timeline][:MAX_TIMELINES]:
            lines += ["", f"<details><summary>timeline of <code>{cell(c.id)}</code></summary>", "",
                      "| Time (s) | Event | Step | Message | Note |", "|--:|---|---|---|---|"]
            lines += [f"| {e['t']:.3f} | {cell(e['event'])} | {cell(e.get('step', ''))} | {cell(e.get('message', ''))} | "
                      f"{cell(e.get('note', ''), MAX_DETAIL)} |" for e in c.timeline[:TIMELINE_LIMIT]]
            lines += ["", "</details>"]
    lines += waiver_table(result)
    return "\n".join(lines) + "\n"


def waiver_table(result: RunResult) -> list[str]:
    """The waived cases by their waiver's reason (folded); nothing if none."""
    reasons = waived(result)
    if not reasons:
        return []
    lines = ["", f"<details><summary>{counted(sum(len(ids) for _, ids in reasons), 'waived case')}, "
             f"{counted(len(reasons), 'reason')}</summary>", "", "| Waiver's reason | Cases | First case |", "|---|--:|---|"]
    lines += [f"| {cell(reason, MAX_DETAIL)} | {len(ids)} | <code>{cell(ids[0])}</code> |" for reason, ids in reasons[:MAX_CAUSES]]
    if len(reasons) > MAX_CAUSES:
        lines += ["", f"and {len(reasons) - MAX_CAUSES} more reasons (see the full report)."]
    return lines + ["", "</details>"]


def cause_table(result: RunResult) -> list[str]:
    """The failures grouped by cause, largest first: a table, then each cause's cases (folded); nothing if none."""
    causes = result.cause_groups()
    if not causes:
        return []
    lines = [f"**Causes** ({len(causes)}, largest first):", "", "| # | Cause | Cases | Messages | Errata | First case |",
             "|--:|---|--:|--:|---|---|"]
    lines += [f"| {n} | {cell(c.title)} | {len(c.cases)} | {len(c.messages)} | {cell(errata_text(c))} | "
              f"<code>{cell(c.cases[0])}</code> |" for n, c in enumerate(causes[:MAX_CAUSES], 1)]
    if len(causes) > MAX_CAUSES:
        lines += ["", f"and {len(causes) - MAX_CAUSES} more causes (see the full report)."]
    lines += ["", "<details><summary>the cases of each cause</summary>", ""]
    for n, c in enumerate(causes[:MAX_CAUSES], 1):
        shown = ", ".join(f"<code>{cell(i)}</code>" for i in c.cases[:MAX_CAUSE_CASES])
        more = f" and {len(c.cases) - MAX_CAUSE_CASES} more" if len(c.cases) > MAX_CAUSE_CASES else ""
        lines.append(f"{n}. {cell(c.title)}: {shown}{more}")
    return lines + ["", "</details>", ""]
