"""The one result model every report renders: a run, its groups (messages, types), their cases and checks.

``RunResult.to_dict()`` is the versioned JSON document (schema: ``vectors/schema/result.schema.json``);
``RunResult.from_dict()`` reads it back, in this format or an older one, so ``imc-conformance report`` can
re-render a saved run exactly.
"""

from __future__ import annotations

import re
from collections import Counter
from dataclasses import asdict, dataclass, field

from .cases import source_case
from .causes import Cause, cause_from, group_causes, regrouped
from .wording import counted
from .verdicts import ATTENTION, UNTESTED, Verdict, failing

FORMAT_NAME = "imc-conformance-result"
VERSION = 6
FORMAT = f"{FORMAT_NAME}/{VERSION}"
SCHEMAS = {1: "result-1.schema.json", 2: "result-2.schema.json", 3: "result-3.schema.json", 4: "result-4.schema.json",
           5: "result-5.schema.json", 6: "result.schema.json"}
INTERRUPTED = 130  # the exit code of a run stopped by Ctrl-C, as shells report SIGINT
NOT_TESTED = ("UNSUPPORTED", "INCONCLUSIVE")  # the verdicts of a group of which nothing was tested


@dataclass(frozen=True)
class ByteDiff:
    """Bytes ``[start, end)`` differ between the expected and actual frame; ``field`` owns them in the expected one."""

    start: int
    end: int
    field: str


@dataclass(slots=True)
class CheckResult:
    check: str
    verdict: Verdict
    detail: str
    outcome: str | None = None  # for acceptable cases: which permitted outcome the implementation chose
    expected: str | None = None  # hex frames, kept for failures so reports can show them side by side
    actual: str | None = None
    diffs: tuple[ByteDiff, ...] = ()
    note: str | None = None  # a remark on how the answer was obtained (Answer.note)
    clause: str | None = None  # the clause this check rests on, where it is not the case's (a scenario step's)
    filed_under: str | None = None  # the group a finding belongs to, where it is not the case's (a reply's bytes)


@dataclass(slots=True)
class Judgement:
    """What a case kind makes of one answer when one check is not enough: several checks (a scenario's steps)
    and the evidence they rest on (a timeline of what was sent and received)."""

    checks: list[CheckResult]
    timeline: list[dict] = field(default_factory=list)


@dataclass
class Incident:
    """Something the adapter did that no single case is to blame for, answered by restarting it and replaying; or a
    live target that stopped sending anything mid-run.

    ``kind``: ``protocol`` (it broke the adapter protocol: the run exits 2), ``crash`` (it died or
    stopped answering, yet each request then succeeded alone: the run exits 1) or ``gone`` (a live target stopped
    sending anything, liveness: what waited on it was decided then, untested; the run exits 1). ``cases``: those in
    flight, or decided then.
    """

    kind: str
    reason: str
    cases: list[str]


@dataclass(slots=True)
class CaseResult:
    id: str
    message: str
    verdict: Verdict
    expect: str | None
    clause: str
    checks: list[CheckResult]
    rule: str | None = None
    errata: list[str] = field(default_factory=list)  # implementation errata that explain a failure
    waiver: str | None = None  # the waiver's reason, when one applies
    timeline: list[dict] = field(default_factory=list)  # a scenario's exchange, entry by entry

    @property
    def notes(self) -> list[str]:
        return list(dict.fromkeys(c.note for c in self.checks if c.note))

    @property
    def detail(self) -> str:
        worst = [c for c in self.checks if c.verdict == self.verdict] or self.checks
        text = "; ".join(f"{c.check}: {c.detail}" for c in worst[:2]) if worst else "no check applies"
        if self.waiver:
            text = f"waived ({self.waiver}); " + text
        return text


@dataclass
class MessageResult:
    """The cases of one group (a message or type of the suite); ``key`` is the suite's identifier for it."""

    name: str
    key: str
    verdict: str  # PASS | FAIL | INCONCLUSIVE or UNSUPPORTED (every case untested)
    cases: list[CaseResult]

    @property
    def counts(self) -> Counter:
        return Counter(c.verdict for c in self.cases)


@dataclass(frozen=True)
class Provenance:
    """What a result is evidence of (format 5 on): the tool that judged, the corpus (the digest of its files), the
    selection of its cases, the implementation errata key and the waivers in effect, and the command line."""

    tool: str  # "imc-conformance <version>"
    corpus: str  # "sha256:<hex>"
    selection: dict  # the options that chose the cases, and how many the selection holds (before any shard)
    errata: str | None  # the errata key failures were labelled with
    waivers: dict | None  # {"file", "sha256", "waivers"}: the waivers file read, or None
    command: list[str]  # the command line, as given

    SHARED = ("tool", "corpus", "selection", "errata", "waivers")  # what the shards of one run have alike

    def differences(self, other: Provenance) -> list[str]:
        """The fields the shards of one run share in which ``other`` differs."""
        return [key for key in self.SHARED if getattr(self, key) != getattr(other, key)]


@dataclass
class RunResult:
    suite: str
    title: str  # how reports name the suite
    edition: str
    implementation: str
    adapter: str
    strict: bool
    started: str
    duration: float  # seconds, rounded to milliseconds (so a saved result renders exactly as the live one)
    messages: list[MessageResult]
    stderr: str = ""
    notes: list[str] = field(default_factory=list)
    complete: bool = True  # False when the run was interrupted: only the cases done so far are in it
    incidents: list[Incident] = field(default_factory=list)
    untested: list[str] = field(default_factory=list)  # check kinds the adapter's hello ruled out entirely
    shard: tuple[int, int] | None = None  # (K, N) of a run of one shard of its selection (--shard K/N)
    provenance: Provenance | None = None  # None: a result of format 1 to 4, or one made without the command line
    causes: list[Cause] | None = None  # the failures grouped by cause (core.causes), made when first asked for
    stale_waivers: list[str] = field(default_factory=list)  # broad waivers (e.g. "cause accepts/rule:crc") that waived
    # nothing of the cases they name: the run fails as for a WAIVER_STALE case
    stopped: bool = False  # not complete because it stopped at its first failing case (--exitfirst), not interrupted
    required: list[str] = field(default_factory=list)  # groups that must be tested (--require; "all": every group
    # of the run): the run fails when one of them is not

    def overall(self) -> str:
        """PASS, FAIL, ERROR (an adapter error), INCONCLUSIVE (nothing could be tested) or INCOMPLETE (interrupted),
        from the exit code."""
        code = self.exit_code()
        if code == 2 and not self.incidents and all(c.verdict in UNTESTED for c in self.cases):
            return "INCONCLUSIVE"
        return {0: "PASS", 1: "FAIL", INTERRUPTED: "INCOMPLETE"}.get(code, "ERROR")

    def untested_groups(self) -> list[str]:
        """The groups of the run whose verdict says nothing was tested (UNSUPPORTED, INCONCLUSIVE)."""
        return [m.name for m in self.messages if m.verdict in NOT_TESTED]

    def unmet_requirements(self) -> list[str]:
        """The required groups (``required``) that were not tested: untested, or (but in a shard, whose other
        shards may hold them) absent from the run."""
        if not self.required:
            return []
        verdicts = {m.name: m.verdict for m in self.messages}
        wanted = list(verdicts) if "all" in self.required else self.required
        return [name for name in wanted if verdicts.get(name, "UNSUPPORTED" if self.shard is None else "PASS")
                in NOT_TESTED]

    def headline(self) -> str:
        """The overall verdict and what it covers: "PASS for 2 of 31 messages; 29 not tested" (never a bare PASS
        when messages went untested); every report opens with it."""
        verdict, total = self.overall(), len(self.messages)
        counts = Counter(m.verdict for m in self.messages)
        untested = counts["UNSUPPORTED"] + counts["INCONCLUSIVE"]
        if untested == total:
            return f"{verdict}, none of {counted(total, 'message')} tested"
        if verdict == "PASS":
            passed = counts["PASS"] + counts["WAIVED"]
            head = ("PASS" + (" with waivers" if counts["WAIVED"] else "") +
                    (f" for all {counted(total, 'message')}" if passed == total > 1 else f" for {passed} of {counted(total, 'message')}"))
            parts = [f"{counts['WAIVED']} with failures waived"] if counts["WAIVED"] else []
        elif counts["FAIL"]:
            head = f"{verdict} for {counts['FAIL']} of {counted(total, 'message')}"
            parts = [f"{counts['PASS']} pass{'es' if counts['PASS'] == 1 else ''}"] if counts["PASS"] else []
        else:
            head = f"{verdict}, {counts['PASS']} of {counted(total, 'message')} pass{'es' if counts['PASS'] == 1 else ''}"
            parts = []
        if counts["WAIVED"] and verdict != "PASS":
            parts.append(f"{counts['WAIVED']} waived")
        if untested:
            parts.append(f"{untested} not tested")
        unmet = self.unmet_requirements()
        if unmet:
            parts.append(f"required but not tested: {', '.join(unmet[:10])}{' ...' if len(unmet) > 10 else ''}")
        return "; ".join([head, *parts])

    def cause_groups(self) -> list[Cause]:
        """The failing and NON_STRICT cases grouped by cause, largest first (as the run grouped them, or from what
        the result keeps)."""
        if self.causes is None:
            self.causes = group_causes(self.cases)
        return self.causes

    @property
    def cases(self) -> list[CaseResult]:
        return [c for m in self.messages for c in m.cases]

    @property
    def summary(self) -> dict[str, int]:
        counts = Counter(c.verdict.value for c in self.cases)
        return {v.value: counts[v.value] for v in Verdict if counts[v.value]}

    def not_passed(self) -> list[str]:
        """The ids of the corpus's cases to run again (``run --last-failed``): those that did not pass (a verdict of
        ``ATTENTION``), a finding filed under another group by the case that made it, in the result's order."""
        return list(dict.fromkeys(source_case(c.id) for c in self.cases if c.verdict in ATTENTION))

    def exit_code(self) -> int:
        """130 if interrupted (not stopped at its first failure); else 2 for an adapter error or protocol violation, or when nothing was tested
        (every case INCONCLUSIVE or UNSUPPORTED; a shard of no case tested all it was given); else 1 for a failing
        verdict, a crash or gone incident, (under --strict) a check kind left untested, a required group
        (``required``) not tested, or a stale waiver (of a whole run: in a shard, another shard may use it); else 0:
        a partial implementation passes for what it does, its other groups reported as not tested."""
        if not self.complete and not self.stopped:
            return INTERRUPTED
        verdicts = {c.verdict for c in self.cases}
        if Verdict.ADAPTER_ERROR in verdicts or any(i.kind == "protocol" for i in self.incidents):
            return 2
        if self.nothing_tested() is not None:
            return 2
        if any(failing(v, self.strict) for v in verdicts) or self.incidents or (self.strict and self.untested) or \
                (self.stale_waivers and self.shard is None) or self.unmet_requirements():
            return 1
        return 0

    def nothing_tested(self) -> str | None:
        """The line saying that nothing could be tested and why (every case INCONCLUSIVE or UNSUPPORTED; a shard of no
        case tested all it was given), or None. Every command judging with this result model prints it."""
        counts = Counter(c.verdict for c in self.cases)
        if not set(counts) <= set(UNTESTED) or not (counts or self.shard is None):
            return None
        if not counts:
            return "nothing could be tested: no case was judged"
        why = ", ".join(f"{n} {v.value}" for v, n in sorted(counts.items(), key=lambda vn: vn[0].value))
        if set(counts) == {Verdict.UNSUPPORTED}:
            why += (" (every answer was \"unsupported\", or a refusal from an implementation shown to do none of what it "
                    "refused: nothing asked of the implementation is implemented yet)")
        return f"nothing could be tested: {why}"

    def to_dict(self) -> dict:
        memo: dict = {}
        return {
            "format": FORMAT, "suite": self.suite, "title": self.title, "edition": self.edition,
            "implementation": self.implementation, "adapter": self.adapter, "strict": self.strict,
            "started": self.started, "duration": self.duration, "complete": self.complete, "summary": self.summary,
            "exit_code": self.exit_code(), "headline": self.headline(), "causes": [c.to_dict() for c in self.cause_groups()], "notes": self.notes, "untested": self.untested,
            "incidents": [asdict(i) for i in self.incidents], "stderr": self.stderr,
            "messages": [{"name": m.name, "key": m.key, "verdict": m.verdict,
                          "counts": {v.value: n for v, n in sorted(m.counts.items())},
                          "cases": [case_dict(c, memo) for c in m.cases]} for m in self.messages],
        } | ({"shard": {"index": self.shard[0], "of": self.shard[1]}} if self.shard else {}) | (
            {"stale_waivers": self.stale_waivers} if self.stale_waivers else {}) | (
            {"required": self.required} if self.required else {}) | (
            {"provenance": asdict(self.provenance)} if self.provenance else {})

    @classmethod
    def from_dict(cls, doc: dict) -> RunResult:
        """A result read back from its JSON document, valid against the schema of this format version."""
        messages = [MessageResult(m["name"], m["key"], m["verdict"], [case_from(c, m["name"]) for c in m["cases"]])
                    for m in doc["messages"]]
        causes = regrouped([c for m in messages for c in m.cases], [cause_from(c) for c in doc.get("causes", ())])
        return cls(doc["suite"], doc["title"], doc["edition"], doc["implementation"], doc["adapter"], doc["strict"],
                   doc["started"], doc["duration"], messages, doc["stderr"], doc["notes"], doc.get("complete", True),
                   [Incident(**i) for i in doc.get("incidents", ())], doc.get("untested", []),
                   (doc["shard"]["index"], doc["shard"]["of"]) if "shard" in doc else None,
                   Provenance(**doc["provenance"]) if "provenance" in doc else None, causes,
                   doc.get("stale_waivers", []),
                   # not complete, yet not exiting as interrupted: stopped at its first failing case
                   not doc.get("complete", True) and doc.get("exit_code", INTERRUPTED) != INTERRUPTED,
                   doc.get("required", []))


def format_version(doc) -> int:
    """The format version of a result document (the current one when it names none, so that the schema
    says what is missing); raises ValueError for a document of another tool or of a newer version."""
    fmt = doc.get("format") if isinstance(doc, dict) else None
    if fmt is None:
        return VERSION
    match = re.fullmatch(re.escape(FORMAT_NAME) + r"/(\d+)", fmt) if isinstance(fmt, str) else None
    if match is None:
        raise ValueError(f"not an imc-conformance result (format {str(fmt)[:80]!r}, expected {FORMAT!r})")
    version = int(match[1])
    if version > VERSION:
        raise ValueError(f"written by a newer version of imc-conformance (format {fmt}); this version reads "
                         f"formats {min(SCHEMAS)} to {VERSION}")
    if version not in SCHEMAS:
        raise ValueError(f"unknown result format {fmt}")
    return version


def message_verdict(cases: list[CaseResult], strict: bool) -> str:
    """FAIL if a case fails; if nothing was tested (no case, or none of the group's valid cases where it has some:
    a refusal by an implementation that reads none of them shows nothing), INCONCLUSIVE when one could not be tested
    and UNSUPPORTED otherwise; WAIVED when a waiver covers a failure; else PASS."""
    if any(failing(c.verdict, strict) for c in cases):
        return "FAIL"
    verdicts = {c.verdict for c in cases}
    if verdicts and verdicts <= set(UNTESTED):
        return "INCONCLUSIVE" if Verdict.INCONCLUSIVE in verdicts else "UNSUPPORTED"
    valid = [c for c in cases if c.expect == "valid"]
    if valid and all(c.verdict in UNTESTED for c in valid):
        return "INCONCLUSIVE" if any(c.verdict is Verdict.INCONCLUSIVE for c in valid) else "UNSUPPORTED"
    if Verdict.WAIVED in verdicts:
        return "WAIVED"
    return "PASS"


def case_dict(c: CaseResult, memo: dict | None = None) -> dict:
    """A case as its JSON form; ``memo`` keeps the form of each check object already written (checks are shared
    between cases where they are equal, e.g. a PASS)."""
    out = {"id": c.id, "verdict": c.verdict.value, "detail": c.detail, "expect": c.expect, "clause": c.clause}
    if c.rule:
        out["rule"] = c.rule
    if c.errata:
        out["errata"] = c.errata
    if c.waiver:
        out["waiver"] = c.waiver
    if c.timeline:
        out["timeline"] = c.timeline
    memo = {} if memo is None else memo
    checks = out["checks"] = []
    for k in c.checks:
        check = memo.get(id(k))
        if check is None:
            check = memo[id(k)] = check_dict(k), k  # the object kept alive, so that its id is not reused
        checks.append(check[0])
    return out


def check_dict(k: CheckResult) -> dict:
    """A check as its JSON form: every field that is set, in the model's order (but where it is filed)."""
    out = {"check": k.check, "verdict": k.verdict.value, "detail": k.detail}
    for key in ("outcome", "expected", "actual"):
        value = getattr(k, key)
        if value is not None:
            out[key] = value
    if k.diffs:
        out["diffs"] = [{"start": d.start, "end": d.end, "field": d.field} for d in k.diffs]
    for key in ("note", "clause"):
        value = getattr(k, key)
        if value is not None:
            out[key] = value
    return out


def case_from(d: dict, message: str) -> CaseResult:
    checks = [CheckResult(k["check"], Verdict(k["verdict"]), k["detail"], k.get("outcome"), k.get("expected"), k.get("actual"),
                          tuple(ByteDiff(**b) for b in k.get("diffs", ())), k.get("note"), k.get("clause"))
              for k in d["checks"]]
    return CaseResult(d["id"], message, Verdict(d["verdict"]), d["expect"], d["clause"], checks, d.get("rule"),
                      d.get("errata", []), d.get("waiver"), d.get("timeline", []))
