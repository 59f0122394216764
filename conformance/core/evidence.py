"""Refusals judged on evidence: a refusal shows something only of an implementation shown to do what it refused.

An implementation that cannot read a message refuses every frame of it, the invalid ones too: that refusal is no
PASS (nor, for a valid frame, a FAIL: the message is not implemented, not tested). A case kind that weighs its
answers so has ``capability(case, request)``, what an answer to a request shows or needs (``decode-le``), and
``evidence(case, edition, request, answer)``, giving
``("shows", capability)`` for an answer that shows the implementation has a capability (it decoded a valid frame:
``decode-le``), ``("needs", capability)`` for one that counts only from an implementation that has it (a refusal),
else None; and ``unproven(check, group, capability)``: what the check becomes where nothing showed it (UNSUPPORTED,
saying why). Capabilities are per group (message, type): a reader of Heartbeat shows nothing of LblRange. A refusal
of a valid input needs ``ANY``: an implementation that reads or writes anything of the group and refuses a valid frame
of it fails that case (it reads little-endian frames and refuses every big-endian one: a defect); one that does
nothing of the group does not implement it.

Where no valid case of the selection can show what a refusal of it may rest on, the case a refused one was made from
(its ``base``), else a valid case of its group, is asked too from the loaded corpus, before the selection's own jobs:
a selection of invalid cases alone (a shard, a rerun of what failed, an interrupted run) is judged as the whole run
would judge them.
"""

from __future__ import annotations

from .cases import Case, expectation
from .results import CheckResult
from .session import Job
from .verdicts import Verdict

ANY = "any"  # the capability a refusal of a valid input rests on: the implementation does anything of the group at all
# what a refusal may be judged, given evidence (a FAIL: a valid frame refused, or an outcome not permitted)
COUNTED = (Verdict.PASS, Verdict.NON_STRICT, Verdict.IMPL_DEFINED, Verdict.FAIL)


class Evidence:
    """What a run's answers showed of the implementation, and the refusals that rest on it."""

    def __init__(self, suite, cases: list[Case], edition: str):
        self.suite, self.edition = suite, edition
        made = {name: suite.kinds[name] for name in {c.kind for c in cases}}  # only the kinds the run plans are made
        self.weighs = {name: kind for name, kind in made.items() if hasattr(kind, "evidence")}
        self.cases = {c.id: c for c in cases if c.kind in self.weighs}
        self.shown: set[tuple[str, str]] = set()  # (group, capability)
        self.needs: list[tuple[Case, CheckResult, str]] = []  # a refusal judged, and the capability it rests on
        self.probes: dict[int, Case] = {}  # id() of each job asked for evidence alone -> the case it is of

    def plan(self, corpus: list[Case], plans: dict, emits: frozenset) -> list[Job]:
        """The jobs asking, for each (group, capability) a refusal in the selection may rest on and none of its valid
        cases can show, the corpus's case that can show it: the base the refused cases name, else the first valid case
        of the group with such a request. Asked before the selection's own jobs (an interrupted run has them)."""
        could_show, could_need = set(), {}
        for case in self.cases.values():
            kind = self.weighs[case.kind]
            valid = expectation(case.data, self.edition) == "valid"
            for request in plans.get(case.id, ()):
                capability = kind.capability(case.data, request)
                if capability is None:
                    continue
                if valid:  # it may show the capability, and (ANY) what a refusal of it rests on
                    could_show.add((case.group, capability))
                else:
                    could_need.setdefault((case.group, capability), case)
        missing = {key: case for key, case in could_need.items() if key not in could_show}
        if not missing or not corpus:
            return []
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
                request = next((r for r in kind.plan(candidate.data, self.edition, emits, {})
                                if kind.capability(candidate.data, r) == capability), None)
                if request is not None:
                    jobs.append(Job(self.suite.name, candidate.id, request))
                    self.probes[id(jobs[-1])] = candidate
                    break
        return jobs

    def answered(self, job: Job, answer, judged: CheckResult | None = None) -> None:
        """Note what an answer shows (a job of the selection, judged ``judged``, or one asked for evidence alone)."""
        if answer.kind != "ok" and answer.kind != "rejected":  # nothing shown, no refusal: the common failures
            return
        case = self.cases.get(job.case_id) if judged is not None else self.probes.get(id(job))
        if case is None:
            return
        said = self.weighs[case.kind].evidence(case.data, self.edition, job.request, answer)
        if said is None:
            return
        if said[0] == "shows":
            self.shown.add((case.group, said[1]))
            self.shown.add((case.group, ANY))
        elif judged is not None and judged.verdict in COUNTED:
            self.needs.append((case, judged, said[1]))

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
