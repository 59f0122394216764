"""What every report format shares: verdict order, the overall verdict, and cleaning implementation text."""

from __future__ import annotations

import re

from ..evaluate import Verdict
from ..results import FAILING, CaseResult, RunResult

VERDICTS = tuple(Verdict)
# The cases a report details: every failing verdict, and NON_STRICT even when it does not fail the run.
ATTENTION = (*FAILING, Verdict.NON_STRICT)

_ANSI = re.compile(r"\x1b\[[0-?]*[ -/]*[@-~]")
_NOT_XML = re.compile("[^\t\n\r\x20-\ud7ff\ue000-\ufffd\U00010000-\U0010ffff]")


def clean(text: str | None) -> str:
    """``text`` without ANSI colour sequences and without characters XML 1.0 forbids (controls, surrogates)."""
    return _NOT_XML.sub("", _ANSI.sub("", text or ""))


def overall(result: RunResult) -> str:
    """PASS, FAIL, or ERROR (an adapter error), from the run's exit code."""
    return {0: "PASS", 1: "FAIL"}.get(result.exit_code(), "ERROR")


def verdict_columns(result: RunResult) -> list[Verdict]:
    """The verdicts that occur in the run, in the model's order: the columns of a per-message table."""
    present = {c.verdict for c in result.cases}
    return [v for v in VERDICTS if v in present]


def attention(result: RunResult) -> list[CaseResult]:
    """The cases a reader must look at, in run order."""
    return [c for c in result.cases if c.verdict in ATTENTION]
