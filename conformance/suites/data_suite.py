"""What the suites share: definitions, rules and errata as JSON files of a data folder, and writing (or checking)
the files a generator builds."""

from __future__ import annotations

import json
from functools import cached_property
from pathlib import Path

from ..core.suite import Suite


class DataSuite(Suite):
    """A suite over a data folder: the packaged one (``packaged``), or one given instead with ``--vectors``."""

    packaged: Path

    def data(self, name: str) -> Path:
        """The folder's own file ``name``, else the packaged one (definitions and rules belong to the suite)."""
        own = self.folder / name
        return own if own.exists() else self.packaged / name

    @cached_property
    def rules(self) -> list[dict]:
        """The rules a refusal may name."""
        return json.loads(self.data("rules.json").read_text(encoding="utf-8"))["rules"]

    @cached_property
    def behaviour(self) -> dict | None:
        """The exchanges file (request/reply rules, and the parameters, effects and services of live cases), or
        None for a suite without one."""
        path = self.data("exchanges.json")
        return json.loads(path.read_text(encoding="utf-8")) if path.exists() else None

    @cached_property
    def statements(self) -> list[dict]:
        """The behavioural statements live cases cite (statements.json), or none."""
        path = self.data("statements.json")
        return json.loads(path.read_text(encoding="utf-8"))["statements"] if path.exists() else []

    def live_problem(self, kind: str, case: dict, params: dict | None = None) -> tuple[str, str] | None:
        """The first problem of a scenario (or robustness probe) the definitions and the exchanges file can see:
        a message, field, value, parameter, effect, service, step or statement they lack; with ``params`` (a
        run's), also a parameter its messages cannot carry."""
        from ..kinds.robustness.kind import as_scenario
        from ..kinds.scenario.lint import lint_scenario

        wire = self.wire
        return lint_scenario(case if kind == "scenario" else as_scenario(case), wire, self.behaviour, self.editions,
                             wire.knows, wire.fields_of, {s["id"]: s for s in self.statements}, params)

    def profile(self, name: str) -> dict:
        """A profile of the folder, else of the packaged data, checked against its schema."""
        from ..files import read_json, schema_error
        from ..paths import VECTORS

        known = sorted({p.stem for folder in (self.folder, self.packaged) for p in (folder / "profiles").glob("*.json")})
        if name not in known:
            raise ValueError(f"unknown profile {name!r} of the suite {self.name!r} (profiles: {', '.join(known) or 'none'})")
        path = self.data(f"profiles/{name}.json")
        _, doc = read_json(path)
        problem = schema_error(VECTORS / "schema" / "profile.schema.json", doc, str(path))
        if problem:
            raise ValueError(problem)
        return doc

    @cached_property
    def errata(self) -> list[dict]:
        """The errata of the folder itself: a corpus given instead brings its own, or none."""
        path = self.folder / "errata.json"
        return json.loads(path.read_text(encoding="utf-8"))["errata"] if path.exists() else []


def write_generated(root: Path, files: dict[str, str], check: bool, label: str) -> int:
    """Write the generated ``files`` (relative to ``root``) and remove case files no longer generated; with
    ``check``, only print what differs (exit code 1 if anything does)."""
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
    print(f"{total} cases in {len(case_files)} files; {len(drift)} written, {len(stale)} removed")
    return 0
