"""The one result model every report renders: a run, its messages, their cases and checks.

``RunResult.to_dict()`` is the versioned JSON document (schema: ``vectors/schema/result.schema.json``);
``RunResult.from_dict()`` reads it back so ``imc-conformance report`` can re-render a saved run.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import asdict, dataclass, field

from .evaluate import ByteDiff, CheckResult, Verdict

FORMAT = "imc-conformance-result/1"
# A message fails if any case has one of these; NON_STRICT joins them under --strict.
FAILING = (Verdict.FAIL, Verdict.CRASH, Verdict.TIMEOUT, Verdict.WAIVER_STALE, Verdict.ADAPTER_ERROR)


@dataclass
class CaseResult:
    id: str
    message: str
    verdict: Verdict
    expect: str
    clause: str
    checks: list[CheckResult]
    rule: str | None = None
    errata: list[str] = field(default_factory=list)  # implementation errata that explain a failure
    waiver: str | None = None  # the waiver's reason, when one applies

    @property
    def detail(self) -> str:
        worst = [c for c in self.checks if c.verdict == self.verdict] or self.checks
        text = "; ".join(f"{c.check}: {c.detail}" for c in worst[:2]) if worst else "no check applies"
        if self.waiver:
            text = f"waived ({self.waiver}); " + text
        return text


@dataclass
class MessageResult:
    name: str
    id: int
    verdict: str  # PASS | FAIL
    cases: list[CaseResult]

    @property
    def counts(self) -> Counter:
        return Counter(c.verdict for c in self.cases)


@dataclass
class RunResult:
    suite: str
    edition: str
    implementation: str
    adapter: str
    strict: bool
    started: str
    duration: float
    messages: list[MessageResult]
    stderr: str = ""
    notes: list[str] = field(default_factory=list)

    @property
    def cases(self) -> list[CaseResult]:
        return [c for m in self.messages for c in m.cases]

    @property
    def summary(self) -> dict[str, int]:
        counts = Counter(c.verdict.value for c in self.cases)
        return {v.value: counts[v.value] for v in Verdict if counts[v.value]}

    def exit_code(self) -> int:
        """2 for an adapter error, else 1 for any failing verdict, else 0."""
        verdicts = {c.verdict for c in self.cases}
        if Verdict.ADAPTER_ERROR in verdicts:
            return 2
        failing = set(FAILING) | ({Verdict.NON_STRICT} if self.strict else set())
        return 1 if verdicts & failing else 0

    def to_dict(self) -> dict:
        return {
            "format": FORMAT, "suite": self.suite, "edition": self.edition, "implementation": self.implementation,
            "adapter": self.adapter, "strict": self.strict, "started": self.started, "duration": round(self.duration, 3),
            "summary": self.summary, "exit_code": self.exit_code(), "notes": self.notes, "stderr": self.stderr,
            "messages": [{"name": m.name, "id": m.id, "verdict": m.verdict,
                          "counts": {v.value: n for v, n in sorted(m.counts.items())},
                          "cases": [case_dict(c) for c in m.cases]} for m in self.messages],
        }

    @classmethod
    def from_dict(cls, doc: dict) -> RunResult:
        if doc.get("format") != FORMAT:
            raise ValueError(f"not an imc-conformance result (format {doc.get('format')!r}, expected {FORMAT!r})")
        messages = [MessageResult(m["name"], m["id"], m["verdict"], [case_from(c, m["name"]) for c in m["cases"]])
                    for m in doc["messages"]]
        return cls(doc["suite"], doc["edition"], doc["implementation"], doc["adapter"], doc["strict"], doc["started"],
                   doc["duration"], messages, doc.get("stderr", ""), doc.get("notes", []))


def message_verdict(cases: list[CaseResult], strict: bool) -> str:
    failing = set(FAILING) | ({Verdict.NON_STRICT} if strict else set())
    return "FAIL" if any(c.verdict in failing for c in cases) else "PASS"


def case_dict(c: CaseResult) -> dict:
    out = {"id": c.id, "verdict": c.verdict.value, "detail": c.detail, "expect": c.expect, "clause": c.clause}
    if c.rule:
        out["rule"] = c.rule
    if c.errata:
        out["errata"] = c.errata
    if c.waiver:
        out["waiver"] = c.waiver
    out["checks"] = []
    for k in c.checks:
        check = {key: value for key, value in asdict(k).items() if value not in (None, ())}
        check["verdict"] = k.verdict.value
        out["checks"].append(check)
    return out


def case_from(d: dict, message: str) -> CaseResult:
    checks = [CheckResult(k["check"], Verdict(k["verdict"]), k["detail"], k.get("outcome"), k.get("expected"), k.get("actual"),
                          tuple(ByteDiff(**b) for b in k.get("diffs", ()))) for k in d["checks"]]
    return CaseResult(d["id"], message, Verdict(d["verdict"]), d["expect"], d["clause"], checks, d.get("rule"),
                      d.get("errata", []), d.get("waiver"))
