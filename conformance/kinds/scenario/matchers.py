"""Field matchers of scenario steps, as data: what a received value must be.

A matcher is a plain value (must equal it) or an object with one of these keys: ``equal``, ``one_of``
(a list), ``range`` (``[min, max]``, either null for no bound, inclusive), ``any``, ``present`` (not
null), ``null``, ``pattern`` (a regular expression the whole text matches), ``contains_item`` (a
``separator``-separated text list holds the item; ``","`` by default). Values are already resolved (enum
names to numbers, parameters to their values) when they reach ``mismatch``.
"""

from __future__ import annotations

import math
import re

KEYS = ("equal", "one_of", "range", "any", "present", "null", "pattern", "contains_item", "contains_message",
        "lacks_message")


def is_matcher(spec) -> bool:
    return isinstance(spec, dict) and len(set(spec) & set(KEYS)) == 1 and set(spec) <= {*KEYS, "separator"}


def mismatch(value, spec) -> str | None:
    """Why ``value`` does not satisfy ``spec``, or None."""
    if not is_matcher(spec):
        return None if same(value, spec) else f"{show(value)}, expected {show(spec)}"
    if "equal" in spec:
        return None if same(value, spec["equal"]) else f"{show(value)}, expected {show(spec['equal'])}"
    if "one_of" in spec:
        if any(same(value, v) for v in spec["one_of"]):
            return None
        return f"{show(value)}, expected one of {', '.join(show(v) for v in spec['one_of'])}"
    if "range" in spec:
        lo, hi = spec["range"]
        if not isinstance(value, (int, float)) or isinstance(value, bool) or math.isnan(value):
            return f"{show(value)} is not a number"
        if (lo is not None and value < lo) or (hi is not None and value > hi):
            return f"{show(value)} outside [{'-inf' if lo is None else lo}, {'inf' if hi is None else hi}]"
        return None
    if "any" in spec:
        return None
    if "present" in spec:
        return "null, expected a value" if value is None else None
    if "null" in spec:
        return None if value is None else f"{show(value)}, expected null"
    if "contains_message" in spec:
        found = spec["contains_message"] in inline_names(value)
        return None if found else f"{show(value)} holds no {spec['contains_message']}"
    if "lacks_message" in spec:
        found = spec["lacks_message"] in inline_names(value)
        return f"{show(value)} holds a {spec['lacks_message']}" if found else None
    if not isinstance(value, str):
        return f"{show(value)} is not text"
    if "pattern" in spec:
        return None if re.fullmatch(spec["pattern"], value) else f"{show(value)} does not match {spec['pattern']!r}"
    items = [item.strip() for item in value.split(spec.get("separator", ","))]
    return None if spec["contains_item"] in items else f"{show(value)} does not list {spec['contains_item']!r}"


def inline_names(value) -> set[str]:
    """The names of every inline message anywhere inside a decoded value."""
    if isinstance(value, list):
        return set().union(*(inline_names(v) for v in value))
    if isinstance(value, dict) and "abbrev" in value:
        return {value["abbrev"]} | inline_names(list(value.get("fields", {}).values()))
    return set()


def same(a, b) -> bool:
    """Equal as decoded values: numbers by value (1 == 1.0), containers element by element."""
    if isinstance(a, bool) or isinstance(b, bool):
        return a is b
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        return a == b
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b))
    return type(a) is type(b) and a == b


def show(value, limit: int = 80) -> str:
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."
