"""Waivers: case ids a team accepts as failing for now, with a reason and an optional expiry date.

File format (JSON, schema ``vectors/schema/waivers.schema.json``): ``{"waivers": [{"id": "<case id>",
"reason": "...", "expires": "2027-03-01"}]}``. Unknown keys (a
typo such as ``expire`` would make a waiver permanent; the schema refuses them), a case waived twice and a
waiver for a case that does not exist are errors; an expired waiver no longer applies (the run notes it);
a waived case that passes is WAIVER_STALE.
"""

from __future__ import annotations

import datetime as dt
from dataclasses import dataclass


class WaiverError(ValueError):
    """A waivers file the run cannot use (unknown keys, unknown or repeated case ids)."""




@dataclass(frozen=True)
class Waiver:
    id: str
    reason: str
    expires: dt.date | None = None


def waivers_in_force(doc: dict, known_ids: set[str], today: dt.date, where: str) -> tuple[dict[str, Waiver], list[str]]:
    """The waivers of a schema-valid document that apply today, by case id, and notes on the expired ones.
    ``where`` names the document in errors."""
    active, notes, seen = {}, [], set()
    for i, entry in enumerate(doc["waivers"]):
        at = f"{where}: $.waivers[{i}]"
        if entry["id"] in seen:
            raise WaiverError(f"{at}.id: {entry['id']!r} is waived twice")
        seen.add(entry["id"])
        if entry["id"] not in known_ids:
            raise WaiverError(f"{at}: no case has the id {entry['id']!r}")
        expires = None
        if "expires" in entry:
            try:
                expires = dt.date.fromisoformat(entry["expires"])
            except ValueError as exc:
                raise WaiverError(f"{at}.expires: {exc}") from exc
        if expires is not None and expires < today:
            notes.append(f"waiver for {entry['id']} expired on {expires.isoformat()} and no longer applies")
            continue
        active[entry["id"]] = Waiver(entry["id"], entry["reason"], expires)
    return active, notes


def waivers_document(failing_ids: list[str], reason: str) -> dict:
    """A starting waivers file listing today's failures."""
    return {"waivers": [{"id": cid, "reason": reason} for cid in failing_ids]}
