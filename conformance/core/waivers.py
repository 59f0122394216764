"""Waivers: failures a team accepts for now, each with a reason and an optional expiry date.

File format (JSON, schema ``vectors/schema/waivers.schema.json``): ``{"waivers": [{"cause": "accepts/rule:crc",
"reason": "...", "expires": "2027-03-01"}]}``; each waiver names exactly one of ``id`` (a case id), ``glob`` (case
ids, ``fnmatch`` style), ``rule`` (the cases breaking a rule) or ``cause`` (a cause key of the report, core.causes).
Unknown keys (a typo such as ``expire`` would make a waiver permanent; the schema refuses them), a waiver given
twice, an id or a glob no case has, a rule the suite lacks and a key that is no cause key are errors; an expired
waiver no longer applies (the run notes it). A waived case that passes is WAIVER_STALE; a glob, rule or cause waiver
applies only to failing cases and is stale when it names cases of the run but none of them fails as it says (the
run then exits 1, as for a WAIVER_STALE case; a shard of a run leaves that to the merge of every shard).

What a case of one group found about another (``core.cases.passive_id``) is waived through the case that made it
(its ``id`` waiver), a glob or its cause. An ADAPTER_ERROR is never waived: it says the adapter, not the
implementation, is broken (and a run that judged nothing has no failure to waive).
"""

from __future__ import annotations

import bisect
import datetime as dt
from dataclasses import dataclass, replace
from fnmatch import fnmatchcase

from .wording import counted
from .cases import source_case
from .causes import cause_of, group_causes, key_problem
from .verdicts import Verdict, failing, worst

KINDS = ("id", "glob", "rule", "cause")  # what a waiver may name, one of them
NEVER = (Verdict.ADAPTER_ERROR,)  # verdicts no waiver covers: the adapter is broken, not the implementation
WILD = "*?["  # what begins the pattern part of a glob


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


def waivable(verdict: Verdict) -> bool:
    """Whether a waiver may cover a case of this verdict (never an ADAPTER_ERROR)."""
    return verdict not in NEVER


def literal_prefix(glob: str) -> str:
    """What every id a glob matches begins with: the glob up to its first wildcard."""
    cut = min((i for i in (glob.find(c) for c in WILD) if i >= 0), default=len(glob))
    return glob[:cut]


def glob_matches(case_id: str, glob: str, prefix: str) -> bool:
    """``fnmatchcase(case_id, glob)`` for an id beginning with the glob's literal ``prefix``: a glob that is its prefix
    and stars alone (``imc/LblRange/crc/*``, the usual kind) matches it without compiling a pattern."""
    return glob.endswith("*") and not glob[len(prefix):].strip("*") or fnmatchcase(case_id, glob)


class Waivers:
    """The waivers in force: by case id, and the broad ones (glob, rule, cause) in file order, the first that
    applies winning. ``stale()``: the broad waivers that named cases of the run but waived none. The broad ones are
    indexed (globs by their literal prefix, rules and causes by name), so that finding a case's waivers costs what
    the waivers naming it cost, not every waiver of the file."""

    def __init__(self, waivers: list[Waiver] = ()):
        self.by_id = {w.name: w for w in waivers if w.by == "id"}
        self.broad = [w for w in waivers if w.by != "id"]
        self.globs: dict[str, list[int]] = {}  # literal prefix: the broad waivers (by index) of globs having it
        self.named_by: dict[tuple[str, str], list[int]] = {}  # (rule, name) or (cause, subject): broad waivers
        for i, w in enumerate(self.broad):
            if w.by == "glob":
                self.globs.setdefault(literal_prefix(w.name), []).append(i)
            else:
                self.named_by.setdefault((w.by, w.name.rsplit("/", 1)[-1] if w.by == "cause" else w.name), []).append(i)
        self.prefix_sizes = sorted({len(p) for p in self.globs})
        self.named: set[Waiver] = set()
        self.used: set[Waiver] = set()

    def __len__(self) -> int:
        return len(self.by_id) + len(self.broad)

    def naming(self, case_id: str, rule: str | None, about: str) -> list[Waiver]:
        """The broad waivers about this case, in file order (``about``: core.causes.about's key, e.g. ``rule:crc``;
        a cause key ends with what its cases are about)."""
        found = [i for size in self.prefix_sizes if size <= len(case_id)
                 for i in self.globs.get(case_id[:size], ()) if glob_matches(case_id, self.broad[i].name, case_id[:size])]
        found += self.named_by.get(("rule", rule), ()) if rule else ()
        found += self.named_by.get(("cause", about), ())
        return [self.broad[i] for i in sorted(found)]

    def find(self, case_id: str, rule: str | None, about: str, cause: str | None) -> Waiver | None:
        """The waiver of a case: its id's (for a finding filed elsewhere, the id of the case that made it), else the
        first broad one naming it that applies to its failure (``cause``: the failure's cause key, None for a case
        that does not fail)."""
        own = self.by_id.get(case_id) or self.by_id.get(source_case(case_id))
        if own is not None:
            return own
        found = None
        for waiver in self.naming(case_id, rule, about):
            self.named.add(waiver)
            if found is None and cause is not None and (waiver.by != "cause" or waiver.name == cause):
                found = waiver
        if found is not None:
            self.used.add(found)
        return found

    def stale(self) -> list[Waiver]:
        return [w for w in self.broad if w in self.named and w not in self.used]


def stale_note(selector: str, shard: tuple[int, int] | None = None) -> str:
    """The note of a broad waiver that waived nothing (the exit code follows ``RunResult.stale_waivers``); in a
    shard, one saying the merge of the shards decides (another shard may use it)."""
    if shard is not None:
        return (f"the waiver of {selector} names cases of the run but waives none of shard {shard[0]}/{shard[1]}'s "
                "(another shard may use it: report --merge of every shard fails the run if none does)")
    return f"WAIVER_STALE: the waiver of {selector} names cases of this run but waives none: it must go"


def waivers_in_force(doc: dict, known_ids: set[str], rules: set[str], subjects: set[str], today: dt.date,
                     where: str) -> tuple[Waivers, list[str]]:
    """The waivers of a schema-valid document that apply today, and notes on the expired ones. ``rules``: the
    suite's; ``subjects``: what a cause key may end with (core.causes.subjects); ``where`` names the document."""
    active, notes, seen = [], [], set()
    ordered = sorted(known_ids)
    for i, entry in enumerate(doc["waivers"]):
        at = f"{where}: $.waivers[{i}]"
        by = next(k for k in KINDS if k in entry)
        name = entry[by]
        if (by, name) in seen:
            raise WaiverError(f"{at}.{by}: {name!r} is waived twice")
        seen.add((by, name))
        if by == "id" and name not in known_ids:
            raise WaiverError(f"{at}: no case has the id {name!r}")
        if by == "glob" and not matches_any(name, ordered):
            raise WaiverError(f"{at}: no case id matches the glob {name!r}")
        if by == "rule" and name not in rules:
            raise WaiverError(f"{at}: the suite has no rule {name!r} ({', '.join(sorted(rules))})")
        if by == "cause":
            problem = key_problem(name, subjects)
            if problem:
                raise WaiverError(f"{at}: {name!r} is not a cause key of this corpus ({problem}; a report's 'Causes' "
                                  "gives them, e.g. 'accepts/rule:crc')")
            if name.split("/", 1)[0] in {v.value.lower() for v in NEVER}:
                raise WaiverError(f"{at}: {name!r} is a cause no waiver covers: an adapter error says the adapter "
                                  "is broken (adapter-check finds what to fix)")
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


def matches_any(glob: str, ordered: list[str]) -> bool:
    """Whether the glob matches an id of ``ordered`` (sorted): only the ids beginning with its literal prefix are
    tried."""
    prefix = literal_prefix(glob)
    for i in range(bisect.bisect_left(ordered, prefix), len(ordered)):
        if not ordered[i].startswith(prefix):
            return False
        if glob_matches(ordered[i], glob, prefix):
            return True
    return False


def to_waive(result) -> tuple[list, list[str]]:
    """The cases of a result (core.results.RunResult) a waivers file written from it covers: those failing as the
    run was asked (NON_STRICT and INCONCLUSIVE under --strict) and those a waiver covered (WAIVED, kept), but never an
    ADAPTER_ERROR, a passing case or a WAIVER_STALE one; and what it says of those it leaves out. A run that judged
    nothing gives none."""
    nothing = result.nothing_tested()
    if nothing is not None:
        return [], [f"no waiver written: {nothing}"]
    out, broken = [], []
    for case in result.cases:
        if case.verdict in NEVER:
            broken.append(case.id)
        elif case.verdict is Verdict.WAIVED or (case.verdict is not Verdict.WAIVER_STALE
                                                and failing(case.verdict, result.strict)):
            out.append(case)
    said = [f"no waiver written for {counted(len(broken), 'ADAPTER_ERROR case')} ({broken[0]}"
            f"{', ...' if len(broken) > 1 else ''}): an adapter error is the adapter's to fix (adapter-check)"] if broken else []
    return out, said


def unwaived(case):
    """A WAIVED case as its checks judged it (its cause is that failure's); any other case as it is."""
    if case.verdict is not Verdict.WAIVED:
        return case
    return replace(case, verdict=worst({c.verdict for c in case.checks}))


def waivers_document(result, reason: str) -> tuple[dict, list[str]]:
    """A waivers file of the run's failures (``to_waive``), one waiver per case: a finding filed under another group
    is waived through the case that made it; a waived case keeps its reason. And notes on what it leaves out."""
    cases, notes = to_waive(result)
    kept: dict[str, str] = {}
    for case in cases:
        kept.setdefault(source_case(case.id), case.waiver or reason)
    return {"waivers": [{"id": cid, "reason": why} for cid, why in kept.items()]}, notes


def cause_waivers_document(result, reason: str, data: dict[str, dict]) -> tuple[dict, list[str]]:
    """A waivers file with one waiver per cause of the run's failures (``to_waive``), each reason saying what the
    cause is and how many cases it covers today (a cause every case of which one waiver covered keeps its reason);
    a case of no cause (INCONCLUSIVE, under --strict) is waived by its id. And notes on what it leaves out.
    ``data``: the cases' records by id (their cause is what the run finds of them, core.causes.cause_of)."""
    cases, notes = to_waive(result)
    plain = [unwaived(c) for c in cases]
    causes = group_causes(plain, lambda c: cause_of(c, data.get(c.id)), errata=False)
    grouped = {cid for c in causes for cid in c.cases}
    reasons = {c.id: c.waiver for c in cases}
    titles = {c.key: c.title for c in result.cause_groups()}  # as the run's reports name them (what the cases share)
    out = []
    for cause in causes:
        given = {reasons[cid] for cid in cause.cases}
        out.append({"cause": cause.key, "reason": given.pop() if len(given) == 1 and None not in given else
                    f"{titles.get(cause.key, cause.title)} ({cause.summary}); {reason}"})
    by_id: dict[str, str] = {}
    for case in plain:
        if case.id not in grouped:
            by_id.setdefault(source_case(case.id), reasons[case.id] or f"{case.verdict.value}: {reason}")
    if by_id:
        notes.append(f"{counted(len(by_id), 'case')} of no cause ({', '.join(sorted({c.verdict.value for c in plain if c.id not in grouped}))}) "
                     "waived by id")
    return {"waivers": out + [{"id": cid, "reason": why} for cid, why in by_id.items()]}, notes
