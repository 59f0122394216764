"""Cases as the runner sees them, and selecting them: by edition, group, id glob and tag."""

from __future__ import annotations

import fnmatch
import hashlib
from dataclasses import dataclass


@dataclass(frozen=True, slots=True)
class Case:
    """A case of a suite: ``data`` is its record as the corpus holds it; ``group`` the message or type it
    is filed under (declared by its file); ``kind`` the case kind that plans and judges it."""

    id: str
    group: str
    kind: str
    data: dict


def passive_id(suite: str, group: str, case_id: str) -> str:
    """The id of what a case found about another group (e.g. the bytes of a reply, under the reply's message)."""
    return f"{suite}/{group}/passive/{case_id.split('/', 1)[1]}"


def source_case(case_id: str) -> str:
    """The case of the corpus a result's case comes from: itself, or the case whose finding it is (``passive_id``)."""
    parts = case_id.split("/", 3)
    return f"{parts[0]}/{parts[3]}" if len(parts) == 4 and parts[2] == "passive" else case_id


def expectation(data: dict, edition: str) -> str | None:
    """``valid`` / ``invalid`` / ``acceptable`` under ``edition``; None if the case is not part of it."""
    expect = data["expect"]
    return expect if isinstance(expect, str) else expect.get(edition)


def shard_of(case_id: str, shards: int) -> int:
    """The shard (1 to ``shards``) a case belongs to: by its id alone (SHA-1), so that adding cases moves none."""
    return int.from_bytes(hashlib.sha1(case_id.encode()).digest()[:8], "big") % shards + 1


def select_cases(cases: list[Case], edition: str, groups=(), globs=(), tags=(),
                 shard: tuple[int, int] | None = None, ids: frozenset[str] | None = None) -> list[Case]:
    """The cases of ``edition``, narrowed to these groups, id globs and tags (each when given), to these ``ids``
    (when not None) and to shard ``(K, N)`` of them."""
    out = []
    for case in cases:
        if ids is not None and case.id not in ids:
            continue
        if shard is not None and shard_of(case.id, shard[1]) != shard[0]:
            continue
        if expectation(case.data, edition) is None:
            continue
        if groups and case.group not in groups:
            continue
        if globs and not any(fnmatch.fnmatchcase(case.id, g) for g in globs):
            continue
        if tags and not set(tags) & set(case.data.get("tags", ())):
            continue
        out.append(case)
    return out
