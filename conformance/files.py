"""Reading the files a run depends on: a suite's case files, waivers, saved results.

Every file is checked against its JSON Schema, and case files also against the suite's definitions, when
it is read; a problem is reported with the file and the JSON path of the first one found
(``200-LblRange.json: $.cases[0].message.fields.range: ...``). The schema check of a case file is
remembered per file content in the cache folder, since over a whole corpus it takes seconds.
"""

from __future__ import annotations

import datetime as dt
import hashlib
from functools import cache
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
from .suites.data_suite import manifest, not_as_built, read_document


def read_json(path: Path, error=ValueError, unique: bool = False):
    """The bytes and the value of a JSON file (``inputs.read_json``: bounded in size and nesting; ``unique``: a key
    given twice in an object refused); ``error`` with one line naming the file if it cannot be read."""
    try:
        return inputs.read_json(path, unique=unique)
    except ValueError as exc:
        raise error(str(exc)) from None


# ---------------------------------------------------------------- case files

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
    """The suite (``open_suite``) and its cases. ``groups``: only the cases of these groups are wanted; the packaged
    corpus then reads only their files (its manifest says which file holds which group), a folder given instead is
    read whole."""
    suite = open_suite(suite_name, directory)
    if directory is None:
        return suite, read_cases(suite, tuple(suite.case_folders.items()), groups=groups)
    folder = Path(directory)
    if suite.folder == folder:
        return suite, read_cases(suite, tuple(suite.case_folders.items()))
    return suite, read_cases(suite, ((folder.name, next(iter(suite.case_folders.values()))),), bare=folder)


def corpus_digest(suite: Suite, directory: Path | None = None) -> str:
    """``sha256:`` of the corpus ``open_corpus(suite.name, directory)`` reads (``DataSuite.corpus_digest`` over the
    folders its case files are read from)."""
    folder = Path(directory) if directory is not None else suite.folder
    own = folder == suite.folder
    return suite.corpus_digest([suite.folder / sub for sub in suite.case_folders] if own else [folder])


@cache
def read_cases(suite: Suite, folders: tuple[tuple[str, str], ...], bare: Path | None = None,
               groups: frozenset[str] | None = None) -> list[Case]:
    """Every case of the suite's case folders (sub-folder name, kind), each file checked unless the packaged
    manifest vouches for its bytes; ids unique; a file the manifest lists is there. ``groups``: skip the packaged
    files the manifest files elsewhere."""
    listed = manifest(suite.packaged) if bare is None and suite.folder == suite.packaged else {}
    cases, seen, found = [], set(), False
    for sub, kind in folders:
        folder = bare or suite.folder / sub
        missing = sorted(name for name, entry in listed.items() if name.startswith(f"{sub}/") and (
            groups is None or entry.get("group") in groups) and not (suite.folder / name).is_file())
        if missing:  # a message left out would pass unseen
            raise not_as_built(suite.packaged, f"{missing[0]} is listed in its manifest but missing")
        for path in sorted(folder.glob("*.json"), key=lambda p: p.name):  # names: faster than comparing paths
            found = True
            entry = listed.get(f"{sub}/{path.name}")
            if groups is not None and entry is not None and entry.get("group") not in groups:
                continue
            for case in read_case_file(suite, kind, path):
                if case.id in seen:
                    raise CorpusError(f"{path}: the case id {case.id} appears twice in the corpus")
                seen.add(case.id)
                cases.append(case)
    if not found:
        raise CorpusError(f"{bare or suite.folder}: no case files (*.json)")
    return cases


def read_case_file(suite: Suite, kind: str, path: Path) -> list[Case]:
    """The cases of one file: a packaged file as the generator recorded it is taken as it is; any other is read
    bounded and checked (schema, then every case against the definitions)."""
    raw, doc, vouched = read_document(path, suite.packaged)
    if vouched:
        group = suite.group_of(doc)
        return [Case(data["id"], group, kind, data) for data in doc["cases"]]
    problem = schema_error(suite.schema(kind), doc, str(path), memo=raw)
    if problem:
        raise CorpusError(problem)
    group = suite.group_of(doc)
    if group not in {g.name for g in suite.groups}:
        raise CorpusError(f"{path}: the file is filed under {group!r}, which is not a {suite.group_label} "
                          f"of the suite {suite.name!r}")
    prefix = f"{suite.name}/{group}/"
    out = []
    for i, data in enumerate(doc["cases"]):
        if not data["id"].startswith(prefix):
            raise CorpusError(f"{path}: $.cases[{i}].id: {data['id']!r} is not under {prefix} (the file's "
                              f"{suite.group_label})")
        problem = suite.case_problem(kind, data)
        if problem:
            raise CorpusError(f"{path}: $.cases[{i}]{problem[0]}: {problem[1]}")
        out.append(Case(data["id"], group, kind, data))
    return out


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
