"""Refusals judged on evidence: a refusal shows something only of an implementation shown to do what it refused.

An implementation that cannot read a message refuses every frame of it, the invalid ones too: that refusal is no
PASS (nor, for a valid frame, a FAIL: the message is not implemented, not tested). A case kind that weighs its answers so has ``evidence(case, edition, request, answer)``, giving
``("shows", capability)`` for an answer that shows the implementation has a capability (it decoded a valid frame:
``decode-le``), ``("needs", capability)`` for one that counts only from an implementation that has it (a refusal),
else None; and ``unproven(check, group, capability)``: what the check becomes where nothing showed it (UNSUPPORTED,
saying why). Capabilities are per group (message, type): a reader of Heartbeat shows nothing of LblRange.

Where the cases run show nothing of a group, the case a refused one was made from (its ``base``), else a valid case
of its group, is asked once more from the loaded corpus: a selection of invalid cases alone is judged as the whole
run would judge them.
"""

from __future__ import annotations

from .cases import Case, expectation
from .results import CheckResult
from .session import Job
from .verdicts import Verdict

# what a refusal may be judged, given evidence (a FAIL: a valid frame refused, or an outcome not permitted)
COUNTED = (Verdict.PASS, Verdict.NON_STRICT, Verdict.IMPL_DEFINED, Verdict.FAIL)


class Evidence:
    """What a run's answers showed of the implementation, and the refusals that rest on it."""

    def __init__(self, suite, cases: list[Case], edition: str):
        self.suite, self.edition = suite, edition
        self.weighs = {name: kind for name, kind in suite.kinds.items() if hasattr(kind, "evidence")}
        self.cases = {c.id: c for c in cases if c.kind in self.weighs}
        self.shown: set[tuple[str, str]] = set()  # (group, capability)
        self.needs: list[tuple[Case, CheckResult, str]] = []  # a refusal judged, and the capability it rests on
        self.asked = 0  # cases asked of the corpus for evidence the selection did not give

    def answered(self, job: Job, answer, judged: CheckResult) -> None:
        case = self.cases.get(job.case_id)
        if case is None:
            return
        said = self.weighs[case.kind].evidence(case.data, self.edition, job.request, answer)
        if said is None:
            return
        if said[0] == "shows":
            self.shown.add((case.group, said[1]))
        elif judged.verdict in COUNTED:
            self.needs.append((case, judged, said[1]))

    def missing(self) -> dict[tuple[str, str], Case]:
        """(group, capability) -> a refused case resting on it, for what nothing showed."""
        return {(c.group, cap): c for c, _, cap in self.needs if (c.group, cap) not in self.shown}

    def probe(self, session, corpus: list[Case], emits: frozenset) -> None:
        """Ask the corpus's case each missing capability can be shown by: the refused case's base, else the first
        valid case of its group with such a check."""
        missing = self.missing()
        if not missing or not corpus:
            return
        by_id = {c.id: c for c in corpus}
        valid: dict[str, list[Case]] = {}
        for c in corpus:
            if c.kind in self.weighs and expectation(c.data, self.edition) == "valid":
                valid.setdefault(c.group, []).append(c)
        jobs = []
        for (group, capability), refused in missing.items():
            base = by_id.get(refused.data.get("base"))
            for candidate in ([base] if base is not None else []) + valid.get(group, []):
                if expectation(candidate.data, self.edition) != "valid":
                    continue
                kind = self.weighs[candidate.kind]
                request = next((r for r in kind.plan(candidate.data, self.edition, emits, {}) if r.check == capability),
                               None)
                if request is not None:
                    jobs.append(Job(self.suite.name, candidate.id, request))
                    break
        self.asked = len(jobs)
        for job, answer in session.run(jobs):
            case = by_id[job.case_id]
            said = self.weighs[case.kind].evidence(case.data, self.edition, job.request, answer)
            if said is not None and said[0] == "shows":
                self.shown.add((case.group, said[1]))

    def review(self, found: dict[str, list[CheckResult]]) -> None:
        """Replace, in each case's checks (``found``, by case id), every refusal resting on what nothing showed."""
        for case, check, capability in self.needs:
            if (case.group, capability) in self.shown:
                continue
            checks = found[case.id]
            for i, k in enumerate(checks):
                if k is check:
                    checks[i] = self.weighs[case.kind].unproven(check, case.group, capability)
                    break
