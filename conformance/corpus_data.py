"""Read the corpus: vector files, rules and errata.

Loading checks the structure the runner relies on and names the file and JSON path of anything
malformed; the full JSON Schema lint of the corpus runs in the project's tests, not on every run.
"""

from __future__ import annotations

import fnmatch
import json
from functools import lru_cache
from pathlib import Path

from .evaluate import expectation
from .paths import imc_data

CHECKS = {"encode-le", "encode-be", "decode-le", "decode-be", "roundtrip"}
EXPECTS = {"valid", "invalid", "acceptable"}


class CorpusError(ValueError):
    """A vector file the runner cannot use; the message names the file and the JSON path."""


def read_vector_file(path: Path) -> dict:
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except json.JSONDecodeError as exc:
        raise CorpusError(f"{path}: not JSON (line {exc.lineno}, column {exc.colno}): {exc.msg}") from exc
    except (OSError, UnicodeDecodeError) as exc:
        raise CorpusError(f"{path}: cannot read: {exc}") from exc
    if not isinstance(doc, dict) or not isinstance(doc.get("cases"), list):
        raise CorpusError(f"{path}: $.cases: expected an array of cases")
    for i, case in enumerate(doc["cases"]):
        problem = case_problem(case)
        if problem:
            where, what = problem
            raise CorpusError(f"{path}: $.cases[{i}]{where}: {what}")
    return doc


def case_problem(case) -> tuple[str, str] | None:
    """(JSON path suffix, problem) for the first structural problem of a case, or None."""
    if not isinstance(case, dict):
        return "", "expected an object"
    if not isinstance(case.get("id"), str) or not case["id"].startswith("imc/") or case["id"].count("/") < 2:
        return ".id", "expected an id like imc/<Message>/<...>"
    expect = case.get("expect")
    values = [expect] if isinstance(expect, str) else list(expect.values()) if isinstance(expect, dict) else [None]
    if not values or any(v not in EXPECTS for v in values):
        return ".expect", f"expected one of {sorted(EXPECTS)} or an object of them per edition, got {expect!r}"
    if not isinstance(case.get("clause"), str):
        return ".clause", "expected a string"
    checks = case.get("checks")
    if not isinstance(checks, list) or not checks or not set(checks) <= CHECKS:
        return ".checks", f"expected a non-empty array of {sorted(CHECKS)}"
    frames = case.get("frames", {})
    if not isinstance(frames, dict):
        return ".frames", "expected an object"
    for order, frame in frames.items():
        if order not in ("le", "be") or not is_hex(frame):
            return f".frames.{order}", "expected hex bytes under 'le' or 'be'"
    for check in checks:
        op, _, order = check.partition("-")
        if op in ("decode", "roundtrip") and order and order not in frames:
            return ".frames", f"check {check} needs a frame in byte order {order}"
        if op in ("encode", "roundtrip") and not isinstance(case.get("message"), dict) and "invalid" not in values:
            return ".message", f"check {check} needs a message"
    if "invalid" in values and not isinstance(case.get("rule"), str):
        return ".rule", "an invalid case names the rule it breaks"
    if "acceptable" in values and not isinstance(case.get("outcomes"), list):
        return ".outcomes", "an acceptable case lists its permitted outcomes"
    return None


def is_hex(text) -> bool:
    """Even-length hex without spaces (bytes.fromhex checks the digits at C speed)."""
    if not isinstance(text, str) or " " in text:
        return False
    try:
        bytes.fromhex(text)
    except ValueError:
        return False
    return True


@lru_cache(maxsize=None)
def vector_files(directory: Path | None = None) -> tuple[tuple[str, dict], ...]:
    """(file name, parsed document) for every vector file of ``directory`` (default: the corpus), in name order."""
    folder = Path(directory) if directory else imc_data("cases")
    paths = sorted(folder.glob("*.json"))
    if not paths:
        raise CorpusError(f"{folder}: no vector files (*.json)")
    return tuple((p.name, read_vector_file(p)) for p in paths)


def load_cases(directory: Path | None = None) -> list[dict]:
    cases = [case for _, doc in vector_files(directory) for case in doc["cases"]]
    seen: set[str] = set()
    for case in cases:
        if case["id"] in seen:
            raise CorpusError(f"{directory or imc_data('cases')}: the case id {case['id']} appears twice")
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
