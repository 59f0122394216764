"""A self-contained HTML compliance report: inline CSS, no external resources, no script.

The template autoescapes everything; implementation text is never marked safe. Failing checks that kept
both frames show them side by side as hex dumps, the differing bytes marked and named by field.
"""

from __future__ import annotations

import json
from functools import cache
from pathlib import Path

from jinja2 import Environment, FileSystemLoader, StrictUndefined
from markupsafe import Markup, escape

from ..core.results import ByteDiff
from ..core.verdicts import Verdict
from ..core.results import FORMAT, CaseResult, RunResult
from ..escaping import clean
from .common import (TIMELINE_LIMIT, attention, cause_numbers, decided_at, errata_text, incident_lines,
                     provenance_lines, verdict_columns, waived)

TEMPLATES = Path(__file__).resolve().parent / "templates"
MAX_DETAILED = 200  # failing cases shown in full
MAX_STDERR = 20_000  # characters of adapter stderr shown
MAX_LEGEND = 40  # differing ranges listed per frame pair
MAX_CAUSE_CASES = 500  # case ids listed under a cause (the JSON result lists them all)
ROW = 16  # bytes per dump row
FULL_DUMP_ROWS = 24  # longer frames show only the rows around differences
TONE = {
    Verdict.PASS: "ok", Verdict.FAIL: "bad", Verdict.CRASH: "bad", Verdict.TIMEOUT: "bad", Verdict.ADAPTER_ERROR: "bad",
    Verdict.NON_STRICT: "warn", Verdict.WAIVER_STALE: "warn", Verdict.IMPL_DEFINED: "info",
    Verdict.UNSUPPORTED: "mute", Verdict.WAIVED: "mute", Verdict.INCONCLUSIVE: "info",
}
GROUP_TONE = {"PASS": "ok", "FAIL": "bad", "INCONCLUSIVE": "info", "UNSUPPORTED": "mute", "WAIVED": "mute"}


@cache
def environment() -> Environment:
    env = Environment(loader=FileSystemLoader(TEMPLATES), autoescape=True, trim_blocks=True, lstrip_blocks=True,
                      undefined=StrictUndefined)
    env.filters["text"] = clean
    env.filters["json_text"] = lambda value: clean(json.dumps(value, ensure_ascii=False))  # autoescaped as text
    return env


def render_html(result: RunResult) -> str:
    failing = attention(result)
    shown = [case_view(c, n) for n, c in enumerate(failing[:MAX_DETAILED])]
    first, anchors = {}, {}
    for view in shown:
        first.setdefault(view["case"].message, view["anchor"])
        anchors[view["case"].id] = view["anchor"]
    numbers = cause_numbers(result)
    for view in shown:
        view["cause"] = numbers.get(view["case"].id)
    causes = [{"n": n, "cause": c, "errata": errata_text(c), "more": max(0, len(c.cases) - MAX_CAUSE_CASES),
               "cases": [(i, anchors.get(i)) for i in c.cases[:MAX_CAUSE_CASES]]}
              for n, c in enumerate(result.cause_groups(), 1)]
    stderr = clean(result.stderr)
    others = [{"case": c, **timeline_view(c)} for c in result.cases if c.timeline and c.id not in anchors]
    return environment().get_template("report.html.j2").render(
        result=result, overall=result.overall(), headline=result.headline(), columns=verdict_columns(result), tone=TONE, failures=shown, causes=causes,
        incidents=incident_lines(result), provenance=provenance_lines(result), format=FORMAT,
        failing_total=len(failing), first_failure=first, group_tone=GROUP_TONE, stderr=stderr[:MAX_STDERR],
        stderr_cut=max(0, len(stderr) - MAX_STDERR), timelines=others,
        waived=[{"reason": r, "cases": ids[:MAX_CAUSE_CASES], "total": len(ids)} for r, ids in waived(result)])


def timeline_view(case: CaseResult) -> dict:
    """A case's timeline as the report shows it: its first entries, which of them decided a step, how many more."""
    return {"timeline": case.timeline[:TIMELINE_LIMIT], "decided": decided_at(case.timeline[:TIMELINE_LIMIT]),
            "timeline_cut": max(0, len(case.timeline) - TIMELINE_LIMIT)}


def case_view(case: CaseResult, index: int) -> dict:
    """A failing case with its frame pairs; checks that produced the same pair share one dump."""
    pairs: dict[tuple, list[str]] = {}
    for k in case.checks:
        if k.expected is not None:
            pairs.setdefault((k.expected, k.actual, k.diffs), []).append(k.check)
    return {"case": case, "anchor": f"case-{index + 1}",
            "frames": [frame_pair(e, a, d, checks) for (e, a, d), checks in pairs.items()], **timeline_view(case)}


def frame_pair(expected: str, actual: str | None, diffs: tuple[ByteDiff, ...], checks: list[str]) -> dict:
    exp = bytes.fromhex(expected)
    act = None if actual is None else bytes.fromhex(actual)
    owner = {i: n for n, d in enumerate(diffs) for i in range(d.start, d.end)}
    rows = visible_rows(max(len(exp), len(act or b"")), {i // ROW for i in owner})
    return {
        "checks": checks,
        "expected": {"size": len(exp), "rows": dump(exp, rows, owner, diffs)},
        "actual": None if act is None else {"size": len(act), "rows": dump(act, rows, owner, diffs)},
        "ranges": [{"n": n, "start": d.start, "end": d.end, "last": d.end - 1, "field": d.field}
                   for n, d in enumerate(diffs[:MAX_LEGEND])],
        "more_ranges": max(0, len(diffs) - MAX_LEGEND),
    }


def visible_rows(size: int, marked: set[int]) -> list[int]:
    """Row numbers to show: all of a short frame; of a long one the first two, the last, and those near a difference."""
    count = -(-size // ROW)
    if count <= FULL_DUMP_ROWS:
        return list(range(count))
    keep = {0, 1, count - 1} | {r + d for r in marked for d in (-1, 0, 1)}
    return sorted(r for r in keep if 0 <= r < count)


def dump(data: bytes, rows: list[int], owner: dict[int, int], diffs: tuple[ByteDiff, ...]) -> list[dict]:
    """Hex dump rows of ``data``, each its offset and its bytes as markup (made here rather than in the template,
    a byte at a time, which cost most of a report): a byte of a differing range is marked with the range's field;
    a marked byte that continues the previous one's range joins its mark, so one mark covers the run. Only hex
    digits and escaped field names go into the markup."""
    out, previous = [], None
    for r in rows:
        if previous is not None and r != previous + 1:
            out.append({"gap": True})
        previous = r
        parts, last = [], None
        for i in range(r * ROW, min(len(data), (r + 1) * ROW)):
            n = owner.get(i)
            sep = "" if i == r * ROW else "  " if i % ROW == ROW // 2 else " "
            hexed = f"{data[i]:02x}"
            if n is None:
                parts.append(sep + hexed)
            else:
                mark = f'<mark class="r{n % 6}" title="{escape(f"{diffs[n].field}, byte {i}")}">'
                parts.append(f"{mark}{sep}{hexed}</mark>" if n == last else f"{sep}{mark}{hexed}</mark>")
            last = n
        out.append({"gap": False, "offset": f"{r * ROW:04x}", "html": Markup("".join(parts)), "empty": not parts})
    return out
