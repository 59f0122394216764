"""The ros_acomms rules and implementation-defined classes (rules.json), as the corpus and the fuzz source use them."""

from __future__ import annotations

import json
from functools import cache

from ..paths import ros_data

ENC = "ros1"


@cache
def rules_document() -> dict:
    return json.loads(ros_data("rules.json").read_text(encoding="utf-8"))


def klass(name: str) -> dict:
    return next(c for c in rules_document()["classes"] if c["id"] == name)


def outcomes(name: str, **frames: bytes) -> list[dict]:
    """The outcomes a class permits, in its order; ``frames``: the bytes of the outcomes that write their own."""
    named = klass(name).get("refusals")
    return [{"outcome": o, **({"frames": {ENC: frames[o].hex()}} if o in frames else {}),
             **({"rules": named} if o == "reject" and named else {})} for o in klass(name)["outcomes"]]
