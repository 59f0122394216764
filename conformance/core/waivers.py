"""Waivers: failures a team accepts for now, each with a reason and an optional expiry date.

File format (JSON, schema ``vectors/schema/waivers.schema.json``): ``{"waivers": [{"cause": "accepts/rule:crc",
"reason": "...", "expires": "2027-03-01"}]}``; each waiver names exactly one of ``id`` (a case id), ``glob`` (case
ids, ``fnmatch`` style), ``rule`` (the cases breaking a rule) or ``cause`` (a cause key of the report, core.causes).
Unknown keys (a typo such as ``expire`` would make a waiver permanent; the schema refuses them), a waiver given
twice, an id or a glob no case has and a rule the suite lacks are errors; an expired waiver no longer applies (the
run notes it). A waived case that passes is WAIVER_STALE; a glob, rule or cause waiver applies only to failing cases
and is stale when it names cases of the run but none of them fails as it says (the run then exits 1, as for a
WAIVER_STALE case).
"""

from __future__ import annotations

import datetime as dt
from dataclasses import dataclass
from fnmatch import fnmatchcase

KINDS = ("id", "glob", "rule", "cause")  # what a waiver may name, one of them


class WaiverError(ValueError):
    """A waivers file the run cannot use (unknown keys, unknown or repeated case ids)."""


@dataclass(frozen=True)
class Waiver:
    by: str  # one of KINDS
    name: str  # the case id, glob, rule or cause key
    reason: str
    expires: dt.date | None = None

    @property
    def selector(self) -> str:
        return f"{self.by} {self.name}"

    def names(self, case_id: str, rule: str | None, about: str) -> bool:
        """Whether the waiver is about this case (``about``: core.causes.about's key, e.g. ``rule:crc``)."""
        if self.by == "id":
            return case_id == self.name
        if self.by == "glob":
            return fnmatchcase(case_id, self.name)
        if self.by == "rule":
            return rule == self.name
        return about == self.name.rsplit("/", 1)[-1]  # a cause key ends with what its cases are about


class Waivers:
    """The waivers in force: by case id, and the broad ones (glob, rule, cause) in file order, the first that
    applies winning. ``stale()``: the broad waivers that named cases of the run but waived none."""

    def __init__(self, waivers: list[Waiver] = ()):
        self.by_id = {w.name: w for w in waivers if w.by == "id"}
        self.broad = [w for w in waivers if w.by != "id"]
        self.named: set[Waiver] = set()
        self.used: set[Waiver] = set()

    def __len__(self) -> int:
        return len(self.by_id) + len(self.broad)

    def find(self, case_id: str, rule: str | None, about: str, cause: str | None) -> Waiver | None:
        """The waiver of a case: its id's, else the first broad one naming it that applies to its failure
        (``cause``: the failure's cause key, None for a case that does not fail)."""
        if case_id in self.by_id:
            return self.by_id[case_id]
        found = None
        for waiver in self.broad:
            if waiver.names(case_id, rule, about):
                self.named.add(waiver)
                if found is None and cause is not None and (waiver.by != "cause" or waiver.name == cause):
                    found = waiver
        if found is not None:
            self.used.add(found)
        return found

    def stale(self) -> list[Waiver]:
        return [w for w in self.broad if w in self.named and w not in self.used]


def stale_note(selector: str) -> str:
    """The note of a broad waiver that waived nothing (the exit code follows ``RunResult.stale_waivers``)."""
    return f"WAIVER_STALE: the waiver of {selector} names cases of this run but waives none: it must go"


def waivers_in_force(doc: dict, known_ids: set[str], rules: set[str], subjects: set[str], today: dt.date,
                     where: str) -> tuple[Waivers, list[str]]:
    """The waivers of a schema-valid document that apply today, and notes on the expired ones. ``rules``: the
    suite's; ``subjects``: what a cause key may end with (core.causes.subjects); ``where`` names the document."""
    active, notes, seen = [], [], set()
    for i, entry in enumerate(doc["waivers"]):
        at = f"{where}: $.waivers[{i}]"
        by = next(k for k in KINDS if k in entry)
        name = entry[by]
        if (by, name) in seen:
            raise WaiverError(f"{at}.{by}: {name!r} is waived twice")
        seen.add((by, name))
        if by == "id" and name not in known_ids:
            raise WaiverError(f"{at}: no case has the id {name!r}")
        if by == "glob" and not any(fnmatchcase(i, name) for i in known_ids):
            raise WaiverError(f"{at}: no case id matches the glob {name!r}")
        if by == "rule" and name not in rules:
            raise WaiverError(f"{at}: the suite has no rule {name!r} ({', '.join(sorted(rules))})")
        if by == "cause" and ("/" not in name or name.rsplit("/", 1)[1] not in subjects):
            raise WaiverError(f"{at}: {name!r} is not a cause key of this corpus (a report's 'Failures by cause' "
                              "gives them, e.g. 'accepts/rule:crc')")
        expires = None
        if "expires" in entry:
            try:
                expires = dt.date.fromisoformat(entry["expires"])
            except ValueError as exc:
                raise WaiverError(f"{at}.expires: {exc}") from exc
        if expires is not None and expires < today:
            notes.append(f"waiver for {by} {name} expired on {expires.isoformat()} and no longer applies")
            continue
        active.append(Waiver(by, name, entry["reason"], expires))
    return Waivers(active), notes


def waivers_document(failing_ids: list[str], reason: str) -> dict:
    """A starting waivers file listing today's failures, one waiver per case."""
    return {"waivers": [{"id": cid, "reason": reason} for cid in failing_ids]}


def cause_waivers_document(causes, reason: str) -> dict:
    """A starting waivers file with one waiver per cause of today's failures (``causes``: core.causes.Cause), each
    reason saying what the cause is and how many cases it covers today."""
    return {"waivers": [{"cause": c.key, "reason": f"{c.title} ({c.summary}); {reason}"} for c in causes
                        if c.key != "waiver-stale"]}
