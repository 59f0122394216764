"""Checking a document against one of the suite's JSON Schemas (``vectors/schema``): the first problem as one line
naming the file and the JSON path. Below the suites and the files they read: both check what they are given here."""

from __future__ import annotations

import json
from functools import cache
from pathlib import Path

from .cache import remembered


@cache
def validator(schema: Path):
    """The schema's bytes and its validator (jsonschema is imported here: only a run that validates pays for it)."""
    from jsonschema import Draft202012Validator

    raw = schema.read_bytes()
    return raw, Draft202012Validator(json.loads(raw))


def schema_error(schema: Path, doc, where: str, memo: bytes | None = None) -> str | None:
    """``<where>: <JSON path>: <problem>`` for the first schema problem of ``doc``, or None. With ``memo`` (the
    file's bytes), a document already found valid is not checked again."""
    raw, check = validator(schema)
    known, record = remembered(schema.name, raw, memo) if memo is not None else (False, lambda: None)
    if known:
        return None
    from jsonschema.exceptions import best_match

    try:
        error = best_match(check.iter_errors(doc))
    except RecursionError:
        return f"{where}: " * bool(where) + "nested too deeply to check"
    if error is None:
        record()
        return None
    return f"{where}: " * bool(where) + f"{error.json_path}: {shorten(error.message)}"


def shorten(text: str, limit: int = 240) -> str:
    return text if len(text) <= limit else text[:limit] + "..."
