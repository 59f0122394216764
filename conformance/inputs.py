"""Reading what comes from outside the suite (a user's files, a recording's comments): bounded in size and in
nesting, every problem a ``ValueError`` of one line.

Any file may be a device or a pipe (``/dev/zero`` is a file): at most ``limit`` bytes are read, whatever it is.
JSON nested deeper than ``JSON_NESTING_LIMIT`` is refused, not a traceback: Python's JSON decoder, the schema
validator and the code that walks a document all recurse.
"""

from __future__ import annotations

import json
import shlex
from pathlib import Path

from .escaping import printable
from .limits import FILE_LIMIT, JSON_NESTING_LIMIT


def read_bytes(path: Path, limit: int = FILE_LIMIT) -> bytes:
    """At most ``limit`` bytes of ``path``; ValueError naming it if it cannot be read or holds more."""
    try:
        with open(path, "rb") as handle:
            data = handle.read(limit + 1)
    except OSError as exc:
        raise ValueError(f"{path}: cannot read: {exc.strerror or exc}") from None
    if len(data) > limit:
        raise ValueError(f"{path}: larger than {limit >> 20} MB, the most the suite reads from one file")
    return data


def read_text(path: Path, limit: int = FILE_LIMIT) -> str:
    """``path`` as UTF-8 text (bounded as ``read_bytes``); ValueError if it is not UTF-8."""
    try:
        return read_bytes(path, limit).decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ValueError(f"{path}: not UTF-8 text: {exc.reason} at byte {exc.start}") from None


def nesting_problem(value, limit: int = JSON_NESTING_LIMIT) -> str | None:
    """Why a parsed JSON value nests too deeply for the code that walks it, or None (an iterative walk)."""
    stack = [(value, 1)]
    while stack:
        item, depth = stack.pop()
        if depth > limit:
            return f"JSON nested deeper than {limit} levels"
        children = item.values() if type(item) is dict else item if type(item) is list else ()
        stack += [(child, depth + 1) for child in children if type(child) in (dict, list)]
    return None


def parse_json(raw: bytes | str, where: str, unique: bool = False):
    """The JSON value of ``raw``; ValueError naming ``where`` if it is not JSON or nests too deeply, or (``unique``)
    if an object gives a key twice (JSON leaves which one counts unsaid: a file that says what to do must not)."""

    def once(pairs: list) -> dict:
        out = {}
        for key, value in pairs:
            if key in out:
                raise ValueError(f"{where}: the key '{printable(key[:40])}' is given twice in one object")
            out[key] = value
        return out
    try:
        value = json.loads(raw, object_pairs_hook=once if unique else None)
    except json.JSONDecodeError as exc:
        raise ValueError(f"{where}: not JSON (line {exc.lineno}, column {exc.colno}): {exc.msg}") from None
    except RecursionError:
        raise ValueError(f"{where}: JSON nested too deeply to read") from None
    except UnicodeDecodeError as exc:
        raise ValueError(f"{where}: not UTF-8 text: {exc.reason} at byte {exc.start}") from None
    problem = nesting_problem(value)
    if problem:
        raise ValueError(f"{where}: {problem}")
    return value


def read_json(path: Path, limit: int = FILE_LIMIT, unique: bool = False) -> tuple[bytes, object]:
    """The bytes of a JSON file and its value; ValueError with the reason (``unique``: see ``parse_json``)."""
    raw = read_bytes(path, limit)
    return raw, parse_json(raw, str(path), unique)


def command_argv(text: str, option: str, missing: str) -> list[str]:
    """The argv of a command given on the command line (split like a shell would, never run by one); ValueError
    naming ``option`` if it cannot be split or is empty (``missing``: what to give instead)."""
    try:
        argv = shlex.split(text)
    except ValueError as exc:
        raise ValueError(f"{option} cannot be split: {exc}") from None
    if not argv:
        raise ValueError(f"{option} is empty (an unset variable?): {missing}")
    return argv
