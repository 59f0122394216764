"""Read the committed corpus: vector files, rules and errata (no validation; the tests lint the data)."""

from __future__ import annotations

import fnmatch
import json
from functools import lru_cache

from .paths import imc_data


@lru_cache(maxsize=None)
def vector_files() -> tuple[tuple[str, dict], ...]:
    """(file name, parsed document) for every vector file, in id order."""
    return tuple((p.name, json.loads(p.read_text(encoding="utf-8"))) for p in sorted(imc_data("cases").glob("*.json")))


def load_cases() -> list[dict]:
    return [case for _, doc in vector_files() for case in doc["cases"]]


@lru_cache(maxsize=None)
def load_errata() -> tuple[dict, ...]:
    return tuple(json.loads(imc_data("errata.json").read_text(encoding="utf-8"))["errata"])


def implementation_errata(case_id: str, implementation: str) -> list[str]:
    """Ids of the implementation errata of ``implementation`` whose case globs match ``case_id``."""
    return [e["id"] for e in load_errata()
            if e.get("implementation") == implementation and any(fnmatch.fnmatchcase(case_id, g) for g in e.get("cases", ()))]
