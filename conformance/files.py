"""Opening what a run depends on: a suite and its corpus (read by ``suites/corpus.py``, the one room that reads case
files), waivers and saved results, each checked against its JSON Schema when read; a problem is reported with the file
and the JSON path of the first one found.
"""

from __future__ import annotations

import datetime as dt
import hashlib
from pathlib import Path

from . import inputs
from .errors import CorpusError
from .core.cases import Case
from .core.results import SCHEMAS, RunResult, format_version, message_verdict
from .core.suite import Suite
from .core.causes import subjects
from .core.waivers import WaiverError, Waivers, waivers_in_force
from .paths import VECTORS
from .schemas import schema_error
from .suites import load_suite
from .suites.corpus import read_corpus


def read_json(path: Path, error=ValueError, unique: bool = False):
    """The bytes and the value of a JSON file (``inputs.read_json``: bounded in size and nesting; ``unique``: a key
    given twice in an object refused); ``error`` with one line naming the file if it cannot be read."""
    try:
        return inputs.read_json(path, unique=unique)
    except ValueError as exc:
        raise error(str(exc)) from None


# ---------------------------------------------------------------- a suite and its corpus

def open_suite(suite_name: str, directory: Path | None = None) -> Suite:
    """The suite over its packaged data, or over ``directory`` given as a suite folder (holding ``cases/`` and maybe
    its own definitions and errata) or as a folder of case files (then its parent's data, if any); CorpusError for
    a folder or suite that cannot be used."""
    try:
        if directory is None:
            return load_suite(suite_name)
        folder = Path(directory)
        if not folder.is_dir():
            raise CorpusError(f"{folder}: {'not a directory' if folder.exists() else 'no such directory'}")
        suite = load_suite(suite_name)
        if any((folder / sub).is_dir() for sub in suite.case_folders):
            return load_suite(suite_name, folder)
        return load_suite(suite_name, folder.parent)
    except LookupError as exc:  # an unknown suite
        raise CorpusError(str(exc)) from exc


def open_corpus(suite_name: str, directory: Path | None = None,
                groups: frozenset[str] | None = None) -> tuple[Suite, list[Case]]:
    """The suite (``open_suite``) and its cases (``suites.corpus.read_corpus``: ``groups``, the groups wanted)."""
    suite = open_suite(suite_name, directory)
    return suite, read_corpus(suite, directory, groups)


def corpus_digest(suite: Suite, directory: Path | None = None) -> str:
    """``sha256:`` of the corpus ``open_corpus(suite.name, directory)`` reads (``DataSuite.corpus_digest`` over the
    folders its case files are read from)."""
    folder = Path(directory) if directory is not None else suite.folder
    own = folder == suite.folder
    return suite.corpus_digest([suite.folder / sub for sub in suite.case_folders] if own else [folder])


# ---------------------------------------------------------------- waivers and saved results

def load_waivers(path: Path, cases: list, rules: set[str], today: dt.date) -> tuple[Waivers, list[str], dict]:
    """The waivers in force, notes on the expired ones, and what a result records of the file (its name as given,
    the SHA-256 of its bytes, how many waivers were in force). ``cases``: the whole corpus; ``rules``: the suite's."""
    raw, doc = read_json(Path(path), WaiverError, unique=True)  # a file that says what to waive
    problem = schema_error(VECTORS / "schema" / "waivers.schema.json", doc, str(path))
    if problem:
        raise WaiverError(problem)
    active, notes = waivers_in_force(doc, {c.id for c in cases}, rules, subjects(cases), today, str(path))
    return active, notes, {"file": str(path), "sha256": hashlib.sha256(raw).hexdigest(), "waivers": len(active)}


def read_result(path: Path) -> RunResult:
    """A saved result (any format version this code knows); ValueError naming the file and the JSON path of a
    problem."""
    _, doc = read_json(Path(path))
    try:
        version = format_version(doc)
    except ValueError as exc:
        raise ValueError(f"{path}: {exc}") from None
    problem = schema_error(VECTORS / "schema" / SCHEMAS[version], doc, str(path))
    if problem:
        raise ValueError(problem)
    if version < 3:  # formats 1 and 2 knew only IMC: numeric message ids, no title (nor, in 1, completeness,
        # incidents or check kinds)
        doc = dict(doc, title="IMC", messages=[dict(m, key=str(m["id"])) for m in doc["messages"]])
    result = RunResult.from_dict(doc)
    for i, m in enumerate(result.messages):
        derived = message_verdict(m.cases, result.strict)
        if m.verdict != derived and version >= 6:
            raise ValueError(f"{path}: $.messages[{i}].verdict: {m.verdict} for {m.name}, whose cases give {derived}: "
                             "a result that contradicts itself is not read")
        m.verdict = derived  # formats 1 to 5 were written before the message verdicts of today (none UNSUPPORTED
        # before 4; before 6, PASS for a message whose valid cases all went untested, or whose failures were waived)
    return result
