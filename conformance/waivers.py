"""Waivers: case ids a team accepts as failing for now, with a reason and an optional expiry date.

File format (JSON): ``{"waivers": [{"id": "imc/LblRange/crc/footer-first-byte/le", "reason": "...",
"expires": "2027-03-01"}]}``. A waiver for a case that does not exist is an error; an expired
waiver no longer applies (the run notes it); a waived case that passes is WAIVER_STALE.
"""

from __future__ import annotations

import datetime as dt
import json
from dataclasses import dataclass
from pathlib import Path


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
    entries = doc.get("waivers") if isinstance(doc, dict) else None
    if not isinstance(entries, list):
        raise WaiverError(f"{path}: expected an object with a 'waivers' array")
    active, notes = {}, []
    for i, entry in enumerate(entries):
        where = f"{path}: $.waivers[{i}]"
        if not isinstance(entry, dict) or not isinstance(entry.get("id"), str) or not isinstance(entry.get("reason"), str):
            raise WaiverError(f"{where}: needs string 'id' and 'reason'")
        if entry["id"] not in known_ids:
            raise WaiverError(f"{where}: no case has the id {entry['id']!r}")
        expires = None
        if entry.get("expires") is not None:
            try:
                expires = dt.date.fromisoformat(entry["expires"])
            except (TypeError, ValueError) as exc:
                raise WaiverError(f"{where}.expires: {exc}") from exc
        if expires is not None and expires < today:
            notes.append(f"waiver for {entry['id']} expired on {expires.isoformat()} and no longer applies")
            continue
        active[entry["id"]] = Waiver(entry["id"], entry["reason"], expires)
    return active, notes


def waivers_document(failing_ids: list[str], reason: str) -> dict:
    """A starting waivers file listing today's failures."""
    return {"waivers": [{"id": cid, "reason": reason} for cid in failing_ids]}
