"""What every report format shares: verdict order, timelines and incidents as text (the
escaping of implementation text is ``escaping``'s)."""

from __future__ import annotations

import json
import shlex

from ..core.causes import Cause
from ..core.results import CaseResult, RunResult
from ..core.verdicts import ATTENTION, Verdict

VERDICTS = tuple(Verdict)
TIMELINE_LIMIT = 60  # timeline entries a report shows per case (the JSON result has them all)


def timeline_lines(case: CaseResult, limit: int = TIMELINE_LIMIT) -> list[str]:
    """A scenario's timeline as text lines: time, event, step, message, fields, note (raw bytes are left to the
    JSON and HTML reports)."""
    lines = []
    for e in case.timeline[:limit]:
        fields = json.dumps(e["fields"], ensure_ascii=False) if "fields" in e else ""
        step = f" [{e['step']}]" if "step" in e else ""
        note = f" — {e['note']}" if "note" in e else ""
        lines.append(f"{e['t']:8.3f} s {e['event']}{step} {e.get('message', '')} {fields}{note}".rstrip())
    if len(case.timeline) > limit:
        lines.append(f"… {len(case.timeline) - limit} more entries in the JSON result")
    return lines


DECIDING = ("timer", "gone", "received", "acknowledged", "refused")  # timeline events that can decide a step


def decided_at(timeline: list[dict]) -> set[int]:
    """The entries of a timeline (by index) that decided a step: of each step, its last frame taken or, when its
    bound ran out, its timer (which names the bound)."""
    last: dict[str, int] = {}
    for i, e in enumerate(timeline):
        if e.get("event") in DECIDING and "step" in e:
            last[e["step"]] = i
    return set(last.values())


def incident_lines(result: RunResult) -> list[str]:
    """One sentence per incident of the run."""
    return [f"{i.kind} incident: {i.reason}; " + ("the" if i.kind == "gone" else "the adapter was restarted and the")
            + f" {len(i.cases)} case(s) " + ("waiting on it were decided then, untested" if i.kind == "gone" else
                                             "in flight replayed one by one")
            + f" ({', '.join(i.cases[:5])}{', ...' if len(i.cases) > 5 else ''})" for i in result.incidents]


def provenance_lines(result: RunResult) -> list[str]:
    """What the result is evidence of, one ``name: value`` line each (``core.results.Provenance``), or one line
    saying it was not recorded."""
    p = result.provenance
    if p is None:
        return ["provenance: not recorded (a result of format 4 or before, or one made without the command line)"]
    chosen = "; ".join(f"{key} {', '.join(map(str, value)) if isinstance(value, list) else value}"
                       for key, value in p.selection.items() if value not in (None, [], False))
    waivers = (f"{p.waivers['file']} (sha256:{p.waivers['sha256']}, {p.waivers['waivers']} in force)" if p.waivers
               else "none")
    return [f"tool: {p.tool}", f"corpus: {p.corpus}", f"selection: {chosen or 'everything'}",
            f"errata key: {p.errata or 'none'}", f"waivers: {waivers}", f"command: {shlex.join(p.command)}"]


def verdict_columns(result: RunResult) -> list[Verdict]:
    """The verdicts that occur in the run, in the model's order: the columns of a per-message table."""
    present = {c.verdict for c in result.cases}
    return [v for v in VERDICTS if v in present]


def attention(result: RunResult) -> list[CaseResult]:
    """The cases a reader must look at, in run order."""
    return [c for c in result.cases if c.verdict in ATTENTION]


def waived(result: RunResult) -> list[tuple[str, list[str]]]:
    """The WAIVED cases grouped by their waiver's reason (first seen first): (reason, case ids in run order)."""
    out: dict[str, list[str]] = {}
    for c in result.cases:
        if c.verdict is Verdict.WAIVED:
            out.setdefault(c.waiver or "", []).append(c.id)
    return list(out.items())


def errata_text(cause: Cause) -> str:
    """The errata explaining a group's cases, with how many each ("P1 828, P2 298"), or ""."""
    return ", ".join(f"{e} {n}" for e, n in cause.errata)


def cause_line(cause: Cause) -> str:
    """A group as one sentence: its title, its size, its first case, the errata that explain it."""
    errata = errata_text(cause)
    return f"{cause.title}: {cause.summary}" + (f" (errata {errata})" if errata else "")


def cause_numbers(result: RunResult) -> dict[str, int]:
    """The number (from 1, largest group first) of each grouped case's cause, by case id."""
    return {case_id: n for n, cause in enumerate(result.cause_groups(), 1) for case_id in cause.cases}
