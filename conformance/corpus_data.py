"""Read the corpus: vector files, rules and errata.

Loading validates every vector file against its JSON Schema (remembered per file content in the cache,
since the schema check of the whole corpus takes seconds) and every message in it against the
definitions, and names the file and JSON path of the first problem.
"""

from __future__ import annotations

import fnmatch
import json
from functools import cache, lru_cache
from pathlib import Path

from jsonschema import Draft202012Validator
from jsonschema.exceptions import best_match

from .cache import remembered
from .decoded_form import message_problem
from .definitions import load_definitions
from .evaluate import expectation
from .paths import VECTORS, imc_data



class CorpusError(ValueError):
    """A vector file the runner cannot use; the message names the file and the JSON path."""


SCHEMA = VECTORS / "schema" / "vectors.schema.json"


@cache
def _schema() -> tuple[bytes, Draft202012Validator]:
    raw = SCHEMA.read_bytes()
    return raw, Draft202012Validator(json.loads(raw))


def read_vector_file(path: Path) -> dict:
    try:
        raw = path.read_bytes()
        doc = json.loads(raw)
    except json.JSONDecodeError as exc:
        raise CorpusError(f"{path}: not JSON (line {exc.lineno}, column {exc.colno}): {exc.msg}") from exc
    except (OSError, UnicodeDecodeError) as exc:
        raise CorpusError(f"{path}: cannot read: {exc}") from exc
    if not isinstance(doc, dict) or not isinstance(doc.get("cases"), list):
        raise CorpusError(f"{path}: $.cases: expected an array of cases")
    schema_raw, validator = _schema()
    known, record = remembered("vector-schema", schema_raw, raw)
    if not known:
        error = best_match(validator.iter_errors(doc))
        if error is not None:
            raise CorpusError(f"{path}: {error.json_path}: {shorten(error.message)}")
        record()
    defs = load_definitions()
    for i, case in enumerate(doc["cases"]):
        problem = message_problem_of(defs, case)
        if problem:
            where, what = problem
            raise CorpusError(f"{path}: $.cases[{i}]{where}: {what}")
    return doc


def shorten(text: str, limit: int = 240) -> str:
    return text if len(text) <= limit else text[:limit] + "..."


def message_problem_of(defs, case: dict) -> tuple[str, str] | None:
    """The first problem of the case's message against the definitions (a decoded form needs its whole header)."""
    if "message" not in case:
        return None
    expects = {case["expect"]} if isinstance(case["expect"], str) else set(case["expect"].values())
    decoded = expects & {"valid", "acceptable"} and any(c.startswith(("decode", "roundtrip")) for c in case["checks"])
    problem = message_problem(defs, case["message"], whole_header=bool(decoded), in_range=True)
    return None if problem is None else (".message" + problem[0], problem[1])


def cases_folder(directory: Path | None) -> Path:
    """The folder of vector files: the corpus's, or ``directory`` given as a suite folder (holding cases/) or as
    the cases folder itself."""
    if directory is None:
        return imc_data("cases")
    folder = Path(directory)
    if not folder.is_dir():
        raise CorpusError(f"{folder}: {'not a directory' if folder.exists() else 'no such directory'}")
    return folder / "cases" if (folder / "cases").is_dir() else folder


@lru_cache(maxsize=None)
def vector_files(directory: Path | None = None) -> tuple[tuple[str, dict], ...]:
    """(file name, parsed document) for every vector file of ``directory`` (default: the corpus), in name order."""
    folder = cases_folder(directory)
    paths = sorted(folder.glob("*.json"))
    if not paths:
        raise CorpusError(f"{folder}: no vector files (*.json)")
    return tuple((p.name, read_vector_file(p)) for p in paths)


def load_cases(directory: Path | None = None) -> list[dict]:
    cases = [case for _, doc in vector_files(directory) for case in doc["cases"]]
    seen: set[str] = set()
    for case in cases:
        if case["id"] in seen:
            raise CorpusError(f"{cases_folder(directory)}: the case id {case['id']} appears twice")
        seen.add(case["id"])
    return cases


def select_cases(cases: list[dict], edition: str, messages=(), globs=(), tags=()) -> list[dict]:
    """The cases of ``edition``, narrowed to these messages, id globs and tags (each when given)."""
    out = []
    for case in cases:
        if expectation(case, edition) is None:
            continue
        if messages and case["id"].split("/")[1] not in messages:
            continue
        if globs and not any(fnmatch.fnmatchcase(case["id"], g) for g in globs):
            continue
        if tags and not set(tags) & set(case["tags"]):
            continue
        out.append(case)
    return out


@lru_cache(maxsize=None)
def load_errata() -> tuple[dict, ...]:
    return tuple(json.loads(imc_data("errata.json").read_text(encoding="utf-8"))["errata"])


def implementation_errata(case_id: str, implementation: str) -> list[str]:
    """Ids of the implementation errata of ``implementation`` whose case globs match ``case_id``."""
    return [e["id"] for e in load_errata()
            if e.get("implementation") == implementation and any(fnmatch.fnmatchcase(case_id, g) for g in e.get("cases", ()))]
