"""Promoted findings: the inputs of shrunk findings kept as a source file of the corpus (``vectors/<suite>/promoted.json``),
with their provenance, which ``imc-conformance generate`` turns into vector cases of their groups.

The file keeps each finding's input (a message, or a frame with the mutation that made it), not its case: the
generator rebuilds the case with the source that found it, in every edition, so a promoted vector always says what
the current reference says. Ids (``<suite>/<group>/fuzz/<hash>``) are the hash of the case's inputs: promoting the
same finding twice adds it once.
"""

from __future__ import annotations

import datetime as dt
import json
import os
from pathlib import Path

from ..inputs import read_json

FORMAT = 1
SCHEMA = "promoted.schema.json"


def entry(finding, seed: int, adapters: list[str], edition: str, version: str, today: dt.date) -> dict:
    """The promoted record of one finding."""
    case = finding.case
    if finding.prop == "message":
        given = {"message": case["message"]}
    else:
        # a frame the reference decodes comes with its encoding in every byte order: each rebuilds the same case
        encoding, frame = next(iter(case["frames"].items()))
        mutation = next((t.split(":", 1)[1] for t in case["tags"] if t.startswith("mutation:")), "none")
        given = {"encoding": encoding, "frame": frame, "mutation": mutation}
    return {"id": case["id"], "group": finding.group, "property": "message" if finding.prop == "message" else "frame",
            "input": given,
            "provenance": {"seed": seed, "adapters": adapters, "edition": edition, "date": today.isoformat(),
                           "rule": case.get("rule"), "finding": finding.classification,
                           "found_by": f"imc-conformance {version}"}}


def read(path: Path, suite: str) -> list[dict]:
    """The promoted records of ``path`` (none if it does not exist yet), checked against their schema; ValueError
    naming the problem if it is not a promoted-findings file of ``suite``."""
    from ..paths import VECTORS
    from ..schemas import schema_error

    if not path.exists():
        return []
    _, doc = read_json(path)
    if not isinstance(doc, dict) or doc.get("suite") != suite:
        raise ValueError(f"{path} is not a promoted-findings file of the suite {suite!r}")
    problem = schema_error(VECTORS / "schema" / SCHEMA, doc, str(path))
    if problem:
        raise ValueError(problem)
    return doc["promoted"]


def merge(path: Path, suite: str, records: list[dict]) -> int:
    """Add ``records`` to the file (created if absent) unless their id is there; the number added. Written to a
    temporary file beside it, then renamed over it."""
    kept = read(path, suite)
    known = {r["id"] for r in kept}
    fresh = [r for r in records if r["id"] not in known and not known.add(r["id"])]
    if not fresh:
        return 0
    doc = {"$schema": f"../schema/{SCHEMA}", "format": FORMAT, "suite": suite,
           "description": "Findings of imc-conformance fuzz, shrunk and promoted (--promote); imc-conformance generate "
                          "makes each a vector case of its group.",
           "promoted": sorted(kept + fresh, key=lambda r: r["id"])}
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    temporary.write_text(json.dumps(doc, indent=1, ensure_ascii=True) + "\n", encoding="utf-8")
    os.replace(temporary, path)
    return len(fresh)


def promoted_cases(records: list[dict], sources: dict[str, object]) -> dict[str, list[dict]]:
    """The vector cases of promoted records by group, rebuilt in every edition (``sources``: edition -> source). A
    case whose expectation differs between editions is one case per expectation, its ``expect`` naming editions."""
    out: dict[str, list[dict]] = {}
    for record in records:
        built = {}
        for edition, source in sources.items():
            if record["group"] not in source.groups:  # a type some edition lacks
                continue
            given = record["input"]
            if record["property"] == "message":
                case = source.case(record["group"], "message", given["message"])
            else:
                case = source.frame_case(record["group"], given["encoding"], bytes.fromhex(given["frame"]),
                                         given["mutation"])
            if case is not None:
                built[edition] = case
        if not built:
            continue
        variants: list[tuple[dict, dict]] = []  # (case without its expectation, edition -> expectation)
        for edition, case in built.items():
            bare = {k: v for k, v in case.items() if k not in ("id", "expect")}
            for known, expects in variants:
                if known == bare:
                    expects[edition] = case["expect"][edition]
                    break
            else:
                variants.append((bare, {edition: case["expect"][edition]}))
        for i, (bare, expects) in enumerate(variants):
            whole = len(expects) == len(sources) and len(set(expects.values())) == 1
            case_id = record["id"] if i == 0 else f"{record['id']}/{min(expects)}"
            group = case_id.split("/")[1]
            out.setdefault(group, []).append({"id": case_id, "expect": next(iter(expects.values())) if whole else expects,
                                              **bare, "provenance": record["provenance"]})
    return out
