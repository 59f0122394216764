"""What every report format shares: verdict order, the overall verdict, and cleaning implementation text."""

from __future__ import annotations

import json
import re

from ..core.results import INTERRUPTED, CaseResult, RunResult
from ..core.verdicts import FAILING, UNTESTED, Verdict

VERDICTS = tuple(Verdict)
# The cases a report details: every failing verdict, and NON_STRICT and INCONCLUSIVE even when they do not fail the run.
ATTENTION = (*FAILING, Verdict.NON_STRICT, Verdict.INCONCLUSIVE)
TIMELINE_LIMIT = 60  # timeline entries a report shows per case (the JSON result has them all)

# The one policy for what an implementation, a node or a capture says, whatever the output (terminal, JSON aside,
# Markdown, HTML, JUnit): every character that could drive a terminal, reorder or hide text, forge a line or break
# XML is shown as an escape (``\x1b``, ``\u202e``), and nothing else is changed: controls (C0 but tab and newline,
# DEL, C1), the Arabic letter mark, zero-width and bidirectional marks, embeddings, overrides and isolates, line and
# paragraph separators, invisible operators, the byte order mark, interlinear annotations, lone surrogates,
# non-characters XML forbids and tag characters. Each renderer then escapes its own markup; the terminal also
# shows newlines as escapes (one line of a log per item).
_UNSAFE = "\x00-\x08\x0b-\x1f\x7f-\x9f\u061c\u200b-\u200f\u2028-\u202e\u2060-\u206f\ufeff\ufff9-\ufffb\ufffe\uffff" \
          "\ud800-\udfff\U000e0000-\U000e007f"
_UNSAFE_TEXT = re.compile(f"[{_UNSAFE}]")
_UNSAFE_LINE = re.compile(f"[{_UNSAFE}\n]")


def _escape(m: re.Match) -> str:
    code = ord(m[0])
    return f"\\x{code:02x}" if code < 0x100 else f"\\u{code:04x}" if code < 0x10000 else f"\\U{code:08x}"


def clean(text: str | None) -> str:
    """Implementation text for a report (Markdown, HTML, JUnit): the unsafe characters shown as escapes, lines
    and tabs kept."""
    return _UNSAFE_TEXT.sub(_escape, text or "")


def printable(text: str | None) -> str:
    """Implementation text for a terminal or a log line: as ``clean``, and newlines shown as escapes too, so that
    it can neither drive the terminal nor forge log lines."""
    return _UNSAFE_LINE.sub(_escape, text or "")


def overall(result: RunResult) -> str:
    """PASS, FAIL, ERROR (an adapter error), INCONCLUSIVE (nothing could be tested) or INCOMPLETE (interrupted),
    from the run's exit code."""
    code = result.exit_code()
    if code == 2 and not result.incidents and all(c.verdict in UNTESTED for c in result.cases):
        return "INCONCLUSIVE"
    return {0: "PASS", 1: "FAIL", INTERRUPTED: "INCOMPLETE"}.get(code, "ERROR")


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


def incident_lines(result: RunResult) -> list[str]:
    """One sentence per incident of the run."""
    return [f"{i.kind} incident: {i.reason}; the adapter was restarted and the {len(i.cases)} case(s) in flight "
            f"replayed one by one ({', '.join(i.cases[:5])}{', ...' if len(i.cases) > 5 else ''})"
            for i in result.incidents]


def verdict_columns(result: RunResult) -> list[Verdict]:
    """The verdicts that occur in the run, in the model's order: the columns of a per-message table."""
    present = {c.verdict for c in result.cases}
    return [v for v in VERDICTS if v in present]


def attention(result: RunResult) -> list[CaseResult]:
    """The cases a reader must look at, in run order."""
    return [c for c in result.cases if c.verdict in ATTENTION]
