"""The result as its versioned JSON document (``imc-conformance-result/<version>``, see ``vectors/schema/result.schema.json``)."""

from __future__ import annotations

import json

from ..core.results import RunResult


def render_json(result: RunResult) -> str:
    return json.dumps(result.to_dict(), indent=1) + "\n"
