"""What every report format shares: verdict order, the overall verdict, and cleaning implementation text."""

from __future__ import annotations

import re

from ..core.results import INTERRUPTED, CaseResult, RunResult
from ..core.verdicts import FAILING, Verdict

VERDICTS = tuple(Verdict)
# The cases a report details: every failing verdict, and NON_STRICT even when it does not fail the run.
ATTENTION = (*FAILING, Verdict.NON_STRICT)

_ANSI = re.compile(r"\x1b\[[0-?]*[ -/]*[@-~]")
# Controls (C0 but tab, DEL, C1), line and paragraph separators, bidirectional and invisible format characters.
_UNPRINTABLE = re.compile("[\x00-\x08\x0a-\x1f\x7f-\x9f\u200b-\u200f\u2028-\u202e\u2060-\u206f\ufeff]")
_NOT_XML = re.compile("[^\t\n\r\x20-\ud7ff\ue000-\ufffd\U00010000-\U0010ffff]")


def clean(text: str | None) -> str:
    """``text`` without ANSI colour sequences and without characters XML 1.0 forbids (controls, surrogates)."""
    return _NOT_XML.sub("", _ANSI.sub("", text or ""))


def printable(text: str | None) -> str:
    """``text`` for a terminal: every control or invisible format character shown as an escape (``\\x1b``,
    ``\\u202e``), so that implementation text can neither drive the terminal nor forge log lines."""
    return _UNPRINTABLE.sub(lambda m: f"\\x{ord(m[0]):02x}" if ord(m[0]) < 0x100 else f"\\u{ord(m[0]):04x}", text or "")


def overall(result: RunResult) -> str:
    """PASS, FAIL, ERROR (an adapter error) or INCOMPLETE (interrupted), from the run's exit code."""
    return {0: "PASS", 1: "FAIL", INTERRUPTED: "INCOMPLETE"}.get(result.exit_code(), "ERROR")


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
