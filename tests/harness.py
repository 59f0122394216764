"""How the project's tests run cases: through the runner, like the command line and the pytest plugin."""

from __future__ import annotations

from pathlib import Path

from imc_conformance.core.runner import run_cases
from imc_conformance.files import open_corpus
from imc_conformance.sessions.library import LibrarySession


def verdicts(adapter_or_session, cases, edition: str, suite_name: str = "imc", strict: bool = False) -> dict:
    """Case id -> (case verdict, check results) for every case of ``cases`` that had a check to make."""
    suite, corpus = open_corpus(suite_name)
    session = adapter_or_session if hasattr(adapter_or_session, "run") else LibrarySession(adapter_or_session, "test")
    result = run_cases(session, suite, cases, edition=edition, adapter="test", strict=strict, corpus=corpus)
    return {c.id: (c.verdict, c.checks) for c in result.cases if c.checks}


def alive(pid: int) -> bool:
    """Whether a process runs (a zombie does not)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (FileNotFoundError, ProcessLookupError):
        return False
    return state != "Z"
