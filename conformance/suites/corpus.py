"""Reading a suite's corpus, in one place: the packaged folder's manifest, every data and case file read bounded and
trusted as built or checked, and a run's cases in one call (``read_corpus``).

The packaged files were checked when they were built (and by the tests), and ``manifest.json`` holds the SHA-256
of each as built: a packaged file whose bytes are those is trusted as it is, without a check at every run. Any
other file (a packaged one changed since, or one of a folder given instead with ``--vectors``: a user's) is read
bounded and checked against its schema (a case file also against the suite's definitions), and a problem is a
corpus error naming the file and the JSON path (``200-LblRange.json: $.cases[0].message.fields.range: ...``). A
folder the suite builds for itself in the cache (the whole protocol's) has a sealed manifest: there a file not as
built is never used, and the folder is damaged (a corpus error, and built again the next time)."""

from __future__ import annotations

import hashlib
import os
from functools import cache
from pathlib import Path

import orjson

from ..core.cases import Case
from ..core.suite import Suite
from ..errors import CorpusError
from ..inputs import parse_json, read_bytes
from ..schemas import schema_error

MANIFEST = "manifest.json"
ALTERED: set[Path] = set()  # packaged folders a file was read from that is not as built (checked, then used)


def read_corpus(suite, directory: Path | None = None, groups: frozenset[str] | None = None) -> list[Case]:
    """The cases of ``suite``: of its own folders, or of ``directory`` given as a folder of case files. ``groups``:
    only the cases of these groups are wanted; the packaged corpus then reads only their files (its manifest says
    which file holds which group), a folder given instead is read whole."""
    if directory is None:
        return read_cases(suite, tuple(suite.case_folders.items()), groups=groups)
    folder = Path(directory)
    if suite.folder == folder:
        return read_cases(suite, tuple(suite.case_folders.items()))
    return read_cases(suite, ((folder.name, next(iter(suite.case_folders.values()))),), bare=folder)


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
        for path in json_files(folder):
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


def json_files(folder: Path) -> list[Path]:
    """The ``*.json`` files of ``folder`` by name (listed by name: a path glob costs a run of one message more than
    reading its file)."""
    try:
        names = os.listdir(folder)
    except OSError:
        return []
    return [folder / name for name in sorted(names) if name.endswith(".json") and not name.startswith(".")]


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


@cache
def manifest_of(packaged: Path) -> tuple[dict[str, dict], bool]:
    """The packaged folder's manifest: file (relative path) -> {"sha256", and for case files "group", "kind"}, and
    whether it is sealed (a folder the suite built for itself: a file not as built makes it damaged); empty (every
    file checked) where there is none or it cannot be read."""
    try:
        doc = orjson.loads(read_bytes(packaged / MANIFEST))
        files, sealed = doc["files"], doc.get("sealed") is True
    except (ValueError, LookupError, TypeError):  # missing, unreadable, not JSON, not a manifest
        return {}, False
    if not isinstance(files, dict):
        return {}, False
    return {name: entry for name, entry in files.items() if isinstance(entry, dict)}, sealed


def manifest(packaged: Path) -> dict[str, dict]:
    """The files of the packaged folder's manifest (``manifest_of``)."""
    return manifest_of(packaged)[0]


def trusted(path: Path, raw: bytes, packaged: Path) -> bool:
    """Whether ``raw`` are the bytes of a packaged file as the generator recorded them."""
    if not path.is_relative_to(packaged):
        return False
    entry = manifest(packaged).get(path.relative_to(packaged).as_posix())
    return isinstance(entry, dict) and entry.get("sha256") == hashlib.sha256(raw).hexdigest()


def not_as_built(packaged: Path, what: str):
    """The CorpusError for a file of the packaged folder that is not as its manifest says (``what``). A sealed folder
    is then damaged: its manifest is removed, so that it is rebuilt the next time it is wanted, and nothing in it is
    used; a folder shipped or generated in a checkout is to be generated again."""
    if not manifest_of(packaged)[1]:
        return CorpusError(f"{packaged}: {what} (run imc-conformance generate, or install again)")
    try:
        (packaged / MANIFEST).unlink()
    except OSError:
        pass
    return CorpusError(f"{packaged}: damaged, {what}: nothing in it is used, and it is built again at the next run")


def read_document(path: Path, packaged: Path) -> tuple[bytes, object, bool]:
    """A data or case file's bytes (read bounded), its JSON value, and whether the packaged manifest vouches for it
    (then it needs no check); CorpusError for a file that cannot be read or is not JSON, and for a file of a sealed
    folder that is not as built."""
    try:
        raw = read_bytes(path)
        if trusted(path, raw, packaged):
            return raw, orjson.loads(raw), True
        if path.is_relative_to(packaged):
            if manifest_of(packaged)[1]:
                raise not_as_built(packaged, f"{path.relative_to(packaged)} is not as built")
            ALTERED.add(packaged)
        return raw, parse_json(raw, str(path)), False
    except ValueError as exc:
        raise CorpusError(str(exc)) from None
