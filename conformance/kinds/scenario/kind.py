"""Sans-IO planning and judging of scenarios: behaviour over a live link, as a case kind of the core.

``admit`` declines scenarios whose effects the run does not allow; ``plan`` turns a scenario into one request the session runs (a ``Program``), or into a verdict
reached without the target: INCONCLUSIVE when a parameter it needs is not given or the profile says it
does not apply, UNSUPPORTED when the target does not claim its capability for the suite (not claimed, or served only
to its own system). ``judge`` turns what the machine found into checks: a failed MUST is FAIL, a failed SHOULD is
NON_STRICT (failing under --strict), an open reading of the seeds (INFO) IMPL_DEFINED, a request the node declined
where the seeds let it (DECLINED) UNSUPPORTED.
"""

from __future__ import annotations

import fnmatch

from ...core.cases import expectation
from ...core.results import CheckResult, Judgement
from ...core.session import Answer, Request
from ...core.verdicts import Verdict
from .machine import Program

ANSWER_VERDICTS = {"crash": Verdict.CRASH, "timeout": Verdict.TIMEOUT, "adapter-error": Verdict.ADAPTER_ERROR,
                   "unsupported": Verdict.UNSUPPORTED, "inconclusive": Verdict.INCONCLUSIVE}


class LiveKind:
    """What the live case kinds share: a case runs when its effects are allowed, is judged without the target
    when it cannot run as asked (``gate``), else becomes one program the session runs; the kind says which
    program (``program``) and where a malformed frame that names no message is filed (``reply_group``)."""

    name: str

    def __init__(self, wire, behaviour: dict):
        self.wire, self.behaviour = wire, behaviour
        self.exchanges = tuple(behaviour["exchanges"])

    def admit(self, case: dict, options: dict) -> str | None:
        return effects_barred(case, options)

    def plan(self, case: dict, edition: str, emits: set[str], options: dict | None = None) -> list[Request]:
        options = options or {}
        if expectation(case, edition) is None:
            return []
        skipped = gate(case, options, self.behaviour)
        if skipped is not None:
            return [skipped]
        program = self.program(case, edition, options)
        return [Request(self.name, "scenario", params={"program": program, "profile": options.get("profile")})]

    def judge(self, case: dict, edition: str, request: Request, answer: Answer) -> CheckResult | Judgement:
        return judgement(case, request, answer, self.reply_group(case))

    def program(self, case: dict, edition: str, options: dict):
        raise NotImplementedError

    def reply_group(self, case: dict) -> str:
        raise NotImplementedError


class ScenarioKind(LiveKind):
    """Scenarios of one suite: its wire, its exchange rules and the vocabulary of its parameters, effects and
    services (``behaviour``: the suite's exchanges file)."""

    name = "scenario"

    def program(self, case: dict, edition: str, options: dict) -> Program:
        return Program(case["id"], case, self.exchanges, self.wire, edition, dict(options.get("params", {})),
                       float(options.get("time_scale", 1.0)), self.behaviour.get("ambiguities", {}),
                       self.behaviour.get("bounds", {}), tuple(self.behaviour.get("silence", ())))

    def reply_group(self, case: dict) -> str:
        """The message a scenario waits for first (where a malformed frame that names none is filed)."""
        for step in case["steps"]:
            for kind in ("expect", "sequence", "silence", "alive"):
                if isinstance(step.get(kind), str):
                    return step[kind]
        return case["steps"][0]["send"]["abbrev"]


def effects_barred(case: dict, options: dict) -> str | None:
    """Why a live case may not run: effects on the target that the run does not allow; or None."""
    allowed = options.get("effects", set())
    barred = [e for e in case.get("effects", ()) if e not in allowed and "all" not in allowed]
    if barred:
        return f"effects not allowed: {', '.join(barred)}; --allow-effects {','.join(barred)} runs them"
    return None


def gate(case: dict, options: dict, behaviour: dict) -> Request | None:
    """A request judged without the target when a live case cannot run as asked: INCONCLUSIVE when a parameter
    it needs is not given or the profile says it does not apply, UNSUPPORTED when the target does not claim its
    capability for the suite (it does not serve it, or serves it only to its own system); else None."""
    params = options.get("params", {})
    missing = [p for p in case.get("needs", ()) if p not in params]
    if missing:
        why = "; ".join(f"--param {p}=... ({behaviour['params'][p]['description']})" for p in missing)
        return skip("INCONCLUSIVE", f"not run: needs {why}")
    claims = options.get("claims")
    capability = case.get("capability")
    if claims is not None and capability is not None and claims.get(capability) != "any":
        what = behaviour["capabilities"][capability]["description"]
        why = ("the target serves it only to its own system, and the suite speaks as another"
               if claims.get(capability) == "self" else "the target does not claim it")
        return skip("UNSUPPORTED", f"not claimed: {capability} ({what}): {why}")
    if claims is None and capability is not None and behaviour["capabilities"][capability].get("claimed_only"):
        what = behaviour["capabilities"][capability]["description"]
        return skip("UNSUPPORTED", f"not claimed: {capability} ({what}): judged only where --claims claims it")
    for rule in (options.get("profile") or {}).get("rules", ()):
        if "not_applicable" in rule and any(fnmatch.fnmatchcase(case["id"], g) for g in rule["scenarios"]):
            return skip("INCONCLUSIVE", f"not applicable under the profile: {rule['not_applicable']} ({rule['citation']})")
    return None


def judgement(case: dict, request: Request, answer: Answer, reply_group: str) -> CheckResult | Judgement:
    """What a machine's record says about a live case: a failed MUST is FAIL, a failed SHOULD (or a check the
    profile relaxes) NON_STRICT; every malformed frame it saw fails the message the frame belongs to
    (``reply_group`` when its header names none)."""
    if request.op == "skip":
        return CheckResult(request.check, Verdict(request.params["verdict"]), request.params["reason"])
    if answer.kind != "ok":
        return CheckResult(request.check, ANSWER_VERDICTS.get(answer.kind, Verdict.ADAPTER_ERROR),
                           answer.reason or answer.kind)
    record = answer.message
    if record.get("error"):
        return Judgement([CheckResult(request.check, Verdict.INCONCLUSIVE, record["error"])], record["timeline"])
    relaxed = relaxations(request.params.get("profile") or {}, case["id"])
    checks = []
    for f in record["findings"]:
        if f.get("inconclusive"):
            checks.append(CheckResult(f["check"], Verdict.INCONCLUSIVE, f["detail"], clause=f["clause"]))
            continue
        level = "SHOULD" if f["check"] in relaxed and relaxable(f["check"]) and f["level"] == "MUST" else f["level"]
        if level == "INFO":  # an open reading of the seeds: what the node chose, never a failure
            checks.append(CheckResult(f["check"], Verdict.IMPL_DEFINED, f["detail"], clause=f["clause"]))
            continue
        if level == "DECLINED":  # the node said it does not do this, where the seeds let it: declining, not failing
            checks.append(CheckResult(f["check"], Verdict.UNSUPPORTED, f["detail"], clause=f["clause"]))
            continue
        verdict = Verdict.PASS if f["passed"] else (Verdict.FAIL if level == "MUST" else Verdict.NON_STRICT)
        detail = f["detail"] if f["passed"] else f"{level}: {f['detail']}"
        checks.append(CheckResult(f["check"], verdict, detail, clause=f["clause"]))
    if not checks:
        checks.append(CheckResult(request.check, Verdict.INCONCLUSIVE, "no step was judged"))
    for frame in record["frames"]:
        ok = frame["problem"] is None
        what = frame["message"] or "a frame"
        verdict, state = ((Verdict.PASS, "is well formed") if ok else
                          (Verdict.INCONCLUSIVE, "was not judged") if frame.get("undecided") else
                          (Verdict.FAIL, "is malformed"))
        checks.append(CheckResult(
            f"bytes-{frame['n']}", verdict, f"{what} received at {frame['t']} s {state}"
            + (f": {frame['problem']}" if not ok else ""),
            clause=frame["clause"] or case["clause"], filed_under=frame["message"] or reply_group))
    return Judgement(checks, record["timeline"])


def skip(verdict: str, reason: str) -> Request:
    return Request("scenario", "skip", params={"verdict": verdict, "reason": reason})


def relaxable(check: str) -> bool:
    """Whether a profile may relax a check: an expectation of a step (step:<id>:<what>), never its arrival."""
    return check.startswith("step:") and check.count(":") == 2


def relaxations(profile: dict, case_id: str) -> set[str]:
    """Checks the profile makes SHOULD for this scenario (never the arrival of a reply itself)."""
    return {c for rule in profile.get("rules", ()) if "relax" in rule
            and any(fnmatch.fnmatchcase(case_id, g) for g in rule["scenarios"]) for c in rule["relax"]}
