"""Field matchers of scenario steps, as data: what a received value must be.

A matcher is a plain value (must equal it) or an object with one of these keys: ``equal``, ``one_of``
(a list), ``none_of`` (a list it must equal none of), ``range`` (``[min, max]``, either null for no bound,
inclusive), ``any``, ``present`` (not
null), ``null``, ``pattern`` (a regular expression the whole text matches), ``contains_item`` (a
``separator``-separated text list, or a list, holds the item; ``","`` by default), ``contains_message`` and
``lacks_message`` (an inline message anywhere inside: a name, or ``{"abbrev", "fields"}`` whose fields it
must hold among its own), ``encoded_at_most`` (the value takes at most that many bytes on the wire, as the
suite's wire counts them), ``bits_within`` and ``bits_below`` (a number of bits at most, or below, 8 times
the bytes of a sibling field named by the matcher), ``all_of`` (a list of matchers, each must hold), ``any_of``
(a list of matchers, one must hold). Values are already resolved (enum names to numbers, parameters to their values)
when they reach ``mismatch``.
"""

from __future__ import annotations

import math
import re

KEYS = ("equal", "one_of", "none_of", "range", "any", "present", "null", "pattern", "contains_item",
        "contains_message", "lacks_message", "encoded_at_most", "bits_within", "bits_below", "all_of", "any_of")


def is_matcher(spec) -> bool:
    return isinstance(spec, dict) and len(set(spec) & set(KEYS)) == 1 and set(spec) <= {*KEYS, "separator"}


def mismatch(value, spec, size_of=None, siblings: dict | None = None) -> str | None:
    """Why ``value`` does not satisfy ``spec``, or None; ``size_of(value)``: its size on the wire in bytes;
    ``siblings``: the other fields of the message it is in."""
    if not is_matcher(spec):
        return None if same(value, spec) else f"{show(value)}, expected {show(spec)}"
    if "equal" in spec:
        return None if same(value, spec["equal"]) else f"{show(value)}, expected {show(spec['equal'])}"
    if "all_of" in spec:
        return "; ".join(filter(None, (mismatch(value, m, size_of, siblings) for m in spec["all_of"]))) or None
    if "any_of" in spec:
        whys = [mismatch(value, m, size_of, siblings) for m in spec["any_of"]]
        return None if None in whys else " and ".join(whys)
    if "none_of" in spec:
        taken = any(same(value, v) for v in spec["none_of"])
        return f"{show(value)}, expected none of {', '.join(show(v) for v in spec['none_of'])}" if taken else None
    if "bits_within" in spec or "bits_below" in spec:
        name = spec.get("bits_within") or spec.get("bits_below")
        data = (siblings or {}).get(name)
        if not isinstance(data, str) or not isinstance(value, int) or isinstance(value, bool):
            return f"{show(value)} cannot be compared with the bits of {name} ({show(data)})"
        bits = 4 * len(data)  # the sibling is bytes as hex
        if "bits_within" in spec:
            return None if value <= bits else f"{value} bits, more than the {bits} bits of {name}"
        return None if value < bits else f"{value} bits, not less than the {bits} bits of {name}"
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
        wanted = spec["contains_message"]
        return None if holds(value, wanted) else f"{show(value)} holds no {show(wanted)}"
    if "lacks_message" in spec:
        wanted = spec["lacks_message"]
        return f"{show(value)} holds {show(wanted)}" if holds(value, wanted) else None
    if "encoded_at_most" in spec:
        size = size_of(value)
        return None if size <= spec["encoded_at_most"] else f"{size} bytes on the wire, at most {spec['encoded_at_most']}"
    if "contains_item" in spec and isinstance(value, list):
        found = any(same(v, spec["contains_item"]) for v in value)
        return None if found else f"{show(value)} does not hold {show(spec['contains_item'])}"
    if not isinstance(value, str):
        return f"{show(value)} is not text"
    if "pattern" in spec:
        return None if re.fullmatch(spec["pattern"], value) else f"{show(value)} does not match {spec['pattern']!r}"
    items = [item.strip() for item in value.split(spec.get("separator", ","))]
    return None if spec["contains_item"] in items else f"{show(value)} does not list {spec['contains_item']!r}"


def holds(value, wanted) -> bool:
    """Whether an inline message matching ``wanted`` (a name, or ``{"abbrev", "fields"}`` with some of its
    fields) is anywhere inside a decoded value."""
    if isinstance(value, list):
        return any(holds(v, wanted) for v in value)
    if not (isinstance(value, dict) and "abbrev" in value):
        return False
    name, fields = (wanted, {}) if isinstance(wanted, str) else (wanted["abbrev"], wanted.get("fields", {}))
    own = value.get("fields", {})
    if value["abbrev"] == name and all(k in own and same(own[k], v) for k, v in fields.items()):
        return True
    return holds(list(own.values()), wanted)


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


def hashable(value):
    """A decoded value usable as a key (lists become tuples, objects sorted tuples of their items)."""
    if isinstance(value, dict):
        return tuple(sorted((k, hashable(v)) for k, v in value.items()))
    return tuple(hashable(v) for v in value) if isinstance(value, list) else value


def show(value, limit: int = 80) -> str:
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."
