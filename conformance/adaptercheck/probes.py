"""The fixed, short set of corpus cases adapter-check sends, chosen from a suite's own byte vectors by what they hold
(never by message): per float the decoded form spells in its own way (−0.0, a NaN's bits at each width, the
infinities, a value needing many digits) and for an inline message field holding none (null, which an implementation
in a managed language may throw on), the first valid case holding one; per class of acceptable cases, the first; per rule of the suite, the first invalid
case breaking it (one breaking that rule alone where there is one). What each invalid probe breaks is its ``flaws``:
what the reference codec, with each rule's check switched off in turn, found when the corpus was generated (and
``generate --check`` proves again).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..core.cases import expectation

# What a valid probe teaches: the feature of a value it holds, in the words adapter-check uses.
FEATURES = {
    "negative-zero": "−0.0",
    "nan-bits-32": "a NaN of a 32-bit float with its own bits (8 hex digits)",
    "nan-bits-64": "a NaN of a 64-bit float with its own bits (16 hex digits)",
    "inf": "the infinity \"inf\"",
    "negative-inf": "the infinity \"-inf\"",
    "many-digits": "a float needing more than 7 significant digits",
    "null-message": "an inline message field holding no message (null)",
    "big-int": "an integer beyond 2^31 (a JSON reader that parses numbers as doubles rounds those beyond 2^53)",
    "empty-text": "an empty text",
    "long-text": "a long text",
    "raw-bytes": "raw bytes, every value 00 to ff",
    "nested": "a message nested in a message",
}
# The features a case's tags name (every tag of the set), for what a value alone does not tell (a text from raw bytes).
TAGGED = {"empty-text": {"text", "class:empty"}, "long-text": {"text", "class:long"},
          "raw-bytes": {"raw", "class:all-bytes"}, "nested": {"nested"}}
BIG = 2 ** 31


@dataclass(frozen=True)
class Probe:
    """A corpus case sent as a probe: ``teaches`` a float feature (valid) or a rule (invalid); ``breaks``: the rules an
    invalid probe's input breaks (any of them is a right rule to name)."""

    case: object  # core.cases.Case
    teaches: str
    breaks: tuple[str, ...] = ()


def features(value, found: set[str]) -> None:
    """Add to ``found`` the float features a decoded value holds (iterative: no recursion a value could drive)."""
    stack = [value]
    while stack:
        item = stack.pop()
        if isinstance(item, dict):
            stack.extend(item.values())
        elif isinstance(item, list):
            stack.extend(item)
        elif isinstance(item, int) and not isinstance(item, bool) and abs(item) >= BIG:
            found.add("big-int")
        elif isinstance(item, float):
            if item == 0 and math.copysign(1.0, item) < 0:
                found.add("negative-zero")
            elif math.isfinite(item) and len(repr(abs(item)).split("e")[0].replace(".", "").strip("0")) > 7:
                found.add("many-digits")
        elif item is None:  # an inline message field holding none: what a managed language's null trips over
            found.add("null-message")
        elif isinstance(item, str):
            if item.startswith("nan:") and len(item) in (12, 20):
                found.add(f"nan-bits-{32 if len(item) == 12 else 64}")
            elif item in ("inf", "-inf"):
                found.add("inf" if item == "inf" else "negative-inf")


def choose(cases: list, edition: str, rules: frozenset[str], reads: set[str] | None = None) -> list[Probe]:
    """The probes, of the groups the adapter reads (``reads``; None: any) where they have one: one valid case per
    feature (one pinning NaN bits for the NaN features), one acceptable case per class (what an implementation may
    accept or refuse: a null list element, an inline message of another type, an enumeration value out of its table,
    which a typed API in a managed language may throw on), one invalid case per rule."""
    valid: dict[str, object] = {}
    acceptable: dict[str, Probe] = {}
    invalid: dict[str, Probe] = {}
    for case in cases:
        data = case.data
        if case.kind != "vector" or not any(c.startswith("decode-") for c in data.get("checks", ())):
            continue
        read = reads is None or case.group in reads
        expect = expectation(data, edition)
        if expect == "valid" and "message" in data and read:
            found: set[str] = set()
            features(data["message"], found)
            tags = set(data.get("tags", ()))
            found.update(name for name, wanted in TAGGED.items() if wanted <= tags)
            pinned = data.get("compare", {}).get("nan_payload", False)
            for feature in sorted(found):
                if feature not in valid and (pinned or not feature.startswith("nan-bits")):
                    valid[feature] = case
        elif expect == "acceptable" and data.get("class"):
            named = "+".join(data["class"]) if isinstance(data["class"], list) else data["class"]
            known = acceptable.get(named)
            if known is None or (read and reads is not None and known.case.group not in reads):
                acceptable[named] = Probe(case, f"class:{named}")
        elif expect == "invalid" and data.get("rule") in rules:
            breaks = tuple(data.get("flaws", {}).get("rules", (data["rule"],)))
            known = invalid.get(data["rule"])
            rank = (not read, len(breaks) > 1)  # of a group it reads, then breaking that rule alone, first
            if known is None or rank < (reads is not None and known.case.group not in reads, len(known.breaks) > 1):
                invalid[data["rule"]] = Probe(case, data["rule"], breaks)
    out = [Probe(valid[f], f) for f in FEATURES if f in valid]
    return out + [acceptable[c] for c in sorted(acceptable)] + [invalid[r] for r in sorted(invalid)]


def first_frames(cases: list, edition: str) -> list:
    """Per group, the valid case a first pass decodes to learn whether the adapter reads the group: the base its
    invalid cases name, else its first valid case with a decode check."""
    bases = {c.data["base"] for c in cases if "base" in c.data}
    out: dict[str, object] = {}
    for case in cases:
        if case.kind != "vector" or expectation(case.data, edition) != "valid" or \
                not any(c.startswith("decode-") for c in case.data.get("checks", ())):
            continue
        if case.group not in out or (case.id in bases and out[case.group].id not in bases):
            out[case.group] = case
    return list(out.values())
