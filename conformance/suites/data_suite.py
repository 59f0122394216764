"""What the suites share: definitions, rules and errata as JSON files of a data folder (read as ``corpus.py`` reads
every file of a corpus: trusted as built by the packaged manifest, or checked against its schema), and writing (or
checking) the files a generator builds, with their manifest."""

from __future__ import annotations

import hashlib
import json
from functools import cached_property
from pathlib import Path

from ..core.suite import Suite
from ..inputs import read_bytes
from ..core.wording import counted
from .corpus import ALTERED, MANIFEST, read_document


def read_data_file(path: Path, schema: str | None, packaged: Path):
    """The JSON document of a suite's data file: as it is when packaged and unchanged, else checked against
    ``schema`` (a file of vectors/schema); CorpusError naming the file and the JSON path of a problem."""
    _, doc, vouched = read_document(path, packaged)
    if vouched or not schema:
        return doc
    from ..errors import CorpusError
    from ..paths import VECTORS
    from ..schemas import schema_error

    problem = schema_error(VECTORS / "schema" / schema, doc, str(path))
    if problem:
        raise CorpusError(problem)
    return doc


class DataSuite(Suite):
    """A suite over a data folder: the packaged one (``packaged``), or one given instead with ``--vectors``."""

    packaged: Path
    data_schemas: dict[str, str] = {}  # a data file -> the schema (in vectors/schema) a user's copy must pass

    def data(self, name: str) -> Path:
        """The folder's own file ``name``, else the packaged one (definitions and rules belong to the suite)."""
        own = self.folder / name
        return own if own.exists() else self.packaged / name

    def read_data(self, name: str, default=None):
        """The document of data file ``name`` (``read_data_file``), or ``default`` where neither folder has it."""
        path = self.data(name)
        if not path.exists():
            return default
        return read_data_file(path, self.data_schemas.get(name), self.packaged)

    @cached_property
    def rules(self) -> list[dict]:
        """The rules a refusal may name."""
        return self.read_data("rules.json")["rules"]

    @cached_property
    def behaviour(self) -> dict | None:
        """The exchanges file (request/reply rules, and the parameters, effects, services and capabilities of live cases) with
        the ambiguity register (``ambiguities``: id -> entry, from ambiguities.json), or None for a suite without
        one."""
        doc = self.read_data("exchanges.json")
        if doc is None:
            return None
        register = self.read_data("ambiguities.json", {"ambiguities": []})["ambiguities"]
        return {**doc, "ambiguities": {a["id"]: a for a in register}}

    @cached_property
    def statements(self) -> list[dict]:
        """The behavioural statements live cases cite (statements.json), or none."""
        return self.read_data("statements.json", {"statements": []})["statements"]

    def live_problem(self, kind: str, case: dict, params: dict | None = None) -> tuple[str, str] | None:
        """The first problem of a scenario (or robustness probe) the definitions and the exchanges file can see:
        a message, field, value, parameter, effect, capability, step or statement they lack; with ``params`` (a
        run's), also a parameter its messages cannot carry."""
        from ..kinds.robustness.phase import as_scenario
        from ..kinds.scenario.lint import lint_scenario

        wire = self.wire
        return lint_scenario(case if kind == "scenario" else as_scenario(case), wire, self.behaviour, self.editions,
                             wire.knows, wire.fields_of, {s["id"]: s for s in self.statements}, params)

    def profile(self, name: str) -> dict:
        """A profile of the folder, else of the packaged data (``read_data_file``: checked against its schema unless
        the manifest vouches for it)."""
        known = sorted({p.stem for folder in (self.folder, self.packaged) for p in (folder / "profiles").glob("*.json")})
        if name not in known:
            raise ValueError(f"unknown profile {name!r} of the suite {self.name!r} (profiles: {', '.join(known) or 'none'})")
        return read_data_file(self.data(f"profiles/{name}.json"), "profile.schema.json", self.packaged)

    def corpus_digest(self, case_folders: list[Path]) -> str:
        """``sha256:`` of the corpus judged with, its case files read from ``case_folders``: of the packaged folder's
        manifest when the suite is over that folder and no file of it was read other than as built (a sealed one's
        never is); else of the name and bytes of every data file the suite uses and every case file of the folders."""
        manifest_path = self.packaged / MANIFEST
        if self.folder == self.packaged and self.packaged not in ALTERED and manifest_path.exists():
            return "sha256:" + hashlib.sha256(read_bytes(manifest_path)).hexdigest()
        profiles = {f"profiles/{p.name}" for folder in (self.folder, self.packaged)
                    for p in (folder / "profiles").glob("*.json")}
        used = [(name, self.data(name)) for name in sorted({*self.data_schemas, *profiles})]
        used += [(f"{folder.name}/{p.name}", p) for folder in case_folders for p in sorted(folder.glob("*.json"))]
        digest = hashlib.sha256()
        for name, path in used:
            if path.exists():
                digest.update(f"{name}\0{hashlib.sha256(read_bytes(path)).hexdigest()}\n".encode())
        return "sha256:" + digest.hexdigest()

    @cached_property
    def errata(self) -> list[dict]:
        """The errata of the folder itself: a corpus given instead brings its own, or none."""
        path = self.folder / "errata.json"
        if not path.exists():
            return []
        return read_data_file(path, self.data_schemas.get("errata.json"), self.packaged)["errata"]


def manifest_entries(files: dict[str, str | bytes], kinds: dict[str, str], group_of) -> dict[str, dict]:
    """The manifest entries of a folder's JSON ``files`` (relative path -> content): the SHA-256 of each, and for a
    case file (under one of the ``kinds`` folders) its group (``group_of(doc)``) and kind."""
    entries = {}
    for name in sorted(n for n in files if n.endswith(".json") and n != MANIFEST):
        data = files[name] if isinstance(files[name], bytes) else files[name].encode("utf-8")
        entry = {"sha256": hashlib.sha256(data).hexdigest()}
        folder = name.split("/")[0]
        if "/" in name and folder in kinds:
            entry.update(group=group_of(json.loads(data)), kind=kinds[folder])
        entries[name] = entry
    return entries


def manifest_text(suite: DataSuite, files: dict[str, str]) -> str:
    """The manifest of the suite's packaged folder once the generated ``files`` are written: the SHA-256 of every
    JSON file in it (case files also with their group and kind), so a run can trust them without checking each."""
    root = suite.packaged
    names = {p.relative_to(root).as_posix() for p in root.rglob("*.json")} | {n for n in files if n.endswith(".json")}
    every = {n: files[n] if n in files else (root / n).read_text(encoding="utf-8") for n in names - {MANIFEST}}
    doc = {"$schema": "../schema/manifest.schema.json", "format": 1, "description": "Written by imc-conformance generate: the SHA-256 of every JSON file of this "
                                       "folder as built and checked; a run trusts a file whose bytes match and checks "
                                       "any other against its schema.",
           "files": manifest_entries(every, suite.case_folders, suite.group_of)}
    return json.dumps(doc, indent=1) + "\n"


def write_generated(suite: DataSuite, files: dict[str, str], check: bool, label: str) -> int:
    """Write the generated ``files`` (relative to the suite's packaged folder) and its manifest, and remove case
    files no longer generated; with ``check``, only print what differs (exit code 1 if anything does)."""
    root = suite.packaged
    files = dict(files)
    files[MANIFEST] = manifest_text(suite, files)
    drift = [name for name, text in files.items()
             if not (root / name).exists() or (root / name).read_text(encoding="utf-8") != text]
    stale = [p.relative_to(root).as_posix() for p in sorted((root / "cases").glob("*.json"))
             if p.relative_to(root).as_posix() not in files]
    if check:
        for name in drift + stale:
            print(f"drift: {label}/{name}")
        return 1 if drift or stale else 0
    (root / "cases").mkdir(exist_ok=True)
    for name in stale:
        (root / name).unlink()
    for name in drift:
        (root / name).write_text(files[name], encoding="utf-8")
    case_files = [t for n, t in files.items() if n.startswith("cases/")]
    total = sum(len(json.loads(t)["cases"]) for t in case_files)
    print(f"{counted(total, 'case')} in {counted(len(case_files), 'file')}; {len(drift)} written, {len(stale)} removed")
    return 0
