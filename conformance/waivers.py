"""Waivers: case ids a team accepts as failing for now, with a reason and an optional expiry date.

File format (JSON, schema ``vectors/schema/waivers.schema.json``): ``{"waivers": [{"id":
"imc/LblRange/crc/footer-first-byte/le", "reason": "...", "expires": "2027-03-01"}]}``. Unknown keys (a
typo such as ``expire`` would make a waiver permanent), a case waived twice and a waiver for a case that
does not exist are errors; an expired waiver no longer applies (the run notes it); a waived case that
passes is WAIVER_STALE.
"""

from __future__ import annotations

import datetime as dt
import json
from dataclasses import dataclass
from functools import cache
from pathlib import Path

from jsonschema import Draft202012Validator
from jsonschema.exceptions import best_match

from .paths import VECTORS


class WaiverError(ValueError):
    pass


@dataclass(frozen=True)
class Waiver:
    id: str
    reason: str
    expires: dt.date | None = None


def load_waivers(path: Path, known_ids: set[str], today: dt.date) -> tuple[dict[str, Waiver], list[str]]:
    """The waivers in force by case id, and notes on the expired ones."""
    try:
        doc = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise WaiverError(f"cannot read waivers {path}: {exc}") from exc
    error = best_match(_validator().iter_errors(doc))
    if error is not None:
        raise WaiverError(f"{path}: {error.json_path}: {error.message[:240]}")
    active, notes, seen = {}, [], set()
    for i, entry in enumerate(doc["waivers"]):
        where = f"{path}: $.waivers[{i}]"
        if entry["id"] in seen:
            raise WaiverError(f"{where}.id: {entry['id']!r} is waived twice")
        seen.add(entry["id"])
        if entry["id"] not in known_ids:
            raise WaiverError(f"{where}: no case has the id {entry['id']!r}")
        expires = None
        if "expires" in entry:
            try:
                expires = dt.date.fromisoformat(entry["expires"])
            except ValueError as exc:
                raise WaiverError(f"{where}.expires: {exc}") from exc
        if expires is not None and expires < today:
            notes.append(f"waiver for {entry['id']} expired on {expires.isoformat()} and no longer applies")
            continue
        active[entry["id"]] = Waiver(entry["id"], entry["reason"], expires)
    return active, notes


@cache
def _validator() -> Draft202012Validator:
    return Draft202012Validator(json.loads((VECTORS / "schema" / "waivers.schema.json").read_text(encoding="utf-8")))


def waivers_document(failing_ids: list[str], reason: str) -> dict:
    """A starting waivers file listing today's failures."""
    return {"waivers": [{"id": cid, "reason": reason} for cid in failing_ids]}
