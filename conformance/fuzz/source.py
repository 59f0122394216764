"""What a suite gives the fuzzer, and what the fuzzer's examples are.

A suite's source builds, from its definitions alone, hypothesis strategies of the inputs of each group (a message or
type) for each property, and turns one drawn input into a vector case in the corpus's own format whose expectation
is the reference codec's. The same function rebuilds a promoted finding from its stored input, so a promoted vector
always says what the current reference says.
"""

from __future__ import annotations

import hashlib
from typing import Protocol

import orjson

# The properties every suite's source offers: generated messages (encode and decode both ways, round trip) and
# mutated frames (decode: the verdict the reference gives the frame, whatever rule the mutation aimed at).
PROPERTIES = ("message", "frame")


class FuzzSource(Protocol):
    suite: str  # the suite's name (first segment of every case id)
    groups: tuple[str, ...]  # every group the source generates for
    mutations: tuple[str, ...]  # the names of its frame mutations

    def inputs(self, group: str, prop: str):
        """A hypothesis strategy of JSON-able inputs of ``prop`` for ``group``."""

    def case(self, group: str, prop: str, drawn) -> dict | None:
        """The vector case of one input (id assigned by ``case_id``), or None where the reference cannot judge it
        (a message too large to frame, a frame beyond the reference's bounds)."""

    def seed_frames(self, group: str) -> list[tuple[str, bytes]]:
        """(encoding, frame) of the group's valid corpus frames: what the fast mutation engine mutates."""

    def mutate(self, group: str, frame: bytes, encoding: str, mutation: str, a: int, b: int) -> bytes:
        """``frame`` with ``mutation`` applied at choices ``a`` and ``b`` (any non-negative integers)."""

    def frame_case(self, group: str, encoding: str, frame: bytes, mutation: str) -> dict | None:
        """The vector case of a (mutated) frame: the reference's verdict on it, or None if it is not judged."""

    def clause(self, group: str) -> str:
        """The clause that defines the group (what a summary of its generated cases cites)."""


def sized_lists(element, largest: int):
    """A strategy of lists of every length up to ``largest``, each length as likely as the others (hypothesis alone
    favours short ones, and a bug that needs five elements would hide)."""
    from hypothesis import strategies as st

    return st.integers(0, largest).flatmap(lambda n: st.lists(element, min_size=n, max_size=n))


def pins_nan(message: dict) -> dict | None:
    """The comparison policy of a case holding a NaN with a payload (``"nan:<bits>"``): its bits are compared."""
    return {"nan_payload": True} if b'"nan:' in orjson.dumps(message) else None


def filed(suite: str, group: str, case: dict, tags, extra: dict) -> dict:
    """A generated case completed: the suite's ``extra`` keys, its tags, and its id ``<suite>/<group>/fuzz/<hash>``,
    the hash of its inputs (frames, message, checks), so that the same finding always gets the same id and
    promoting it twice adds it once."""
    case.update(extra)
    case["tags"] = sorted(set(tags))
    key = orjson.dumps({k: case.get(k) for k in ("frames", "message", "checks")}, option=orjson.OPT_SORT_KEYS)
    case["id"] = f"{suite}/{group}/fuzz/{hashlib.sha256(key).hexdigest()[:12]}"
    return case


def valid_frames(cases, edition: str) -> dict[str, list[tuple[str, bytes]]]:
    """(encoding, frame) of the vector cases of each group of a loaded corpus that are valid in ``edition``."""
    from ..core.cases import expectation

    out: dict[str, list[tuple[str, bytes]]] = {}
    for c in cases:
        if c.kind == "vector" and "frames" in c.data and expectation(c.data, edition) == "valid":
            out.setdefault(c.group, []).extend((e, bytes.fromhex(h)) for e, h in c.data["frames"].items())
    return out
