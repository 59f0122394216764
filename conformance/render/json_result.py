"""The result as its versioned JSON document (``imc-conformance-result/<version>``, see ``vectors/schema/result.schema.json``),
written by orjson (the result of a whole corpus is megabytes: the standard library's encoder took 40 µs a case)."""

from __future__ import annotations

import json

import orjson

from ..core.results import RunResult


def render_json(result: RunResult) -> str:
    doc = result.to_dict()
    try:
        return orjson.dumps(doc, option=orjson.OPT_INDENT_2 | orjson.OPT_APPEND_NEWLINE).decode("utf-8")
    except orjson.JSONEncodeError:  # text orjson will not write (a lone surrogate an implementation sent): escaped
        return json.dumps(doc, indent=2) + "\n"
