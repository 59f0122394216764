"""One scenario as a sans-IO state machine: events in (something received at t, time passed), data out
(what to send), findings and a timeline kept. No clock, no socket: the caller says what time it is.

Steps (each names its ``id``, ``level`` MUST or SHOULD, and ``clause``):
``send`` a message; ``expect`` a message within a bound (a reply to an earlier send, correlated by the
exchange rules, resent after the bound if the exchange is idempotent; or any such message, ``count`` of
them); ``sequence``: replies passing through progress states to exactly one terminal state, then
nothing more for a quiet period; ``silence``: no such message (with its ``fields``, where it gives them) for a
while; ``alive``: the node still
sends something; ``wait``.

Levels come from the seeds' words: a step is MUST or SHOULD, and the rules of a sequence's states carry the level
of the text they rest on (exchanges.json); an ``expect`` step may check more of the same reply at a weaker level
(``also``: a SHOULD, or a reading). Where the seeds leave the reading open (the ambiguity register), the node's
choice is an INFO check naming the register's entry, never a failure: a state that may end a request or delay it
(BUSY: the sequence then listens until its own bound), a state value the definitions do not name, silence where the
seeds define no reply (the exchange's ``silence`` or the rules for every request, selecting a request by its fields,
a system nobody answers for, an id an earlier request still carries or an address elsewhere; or ``if_silent`` on a
step that awaits something other than a reply). A sequence ending in a state that declines the request where the
seeds let a node (the operation is not supported) is a DECLINED check: the node is shown declining, not failing.
Bounds are seconds or the names of the suite's timing bounds, each saying where it comes from.

A step that fails for want of a frame (no reply, no terminal state) while the session could not see everything
(the link reported an impairment: the kernel dropped datagrams) or while a frame of the awaited message could
not be judged is INCONCLUSIVE, never FAIL: the missing frame may have been among those the suite did not see.
While another system uses the session's id (a lasting impairment) every failure is INCONCLUSIVE: the other's
replies and the session's cannot be told apart, nor can the replies it took away.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

from .exchanges import exchange_for
from .judging import Judging
from .matchers import hashable
from .receiving import Receiving
from .records import STEP_KINDS, Finding, Frame, StepState, step_length
from .replies import Replies
from .values import Scope, Unresolved, resolve_message, resolve_plain
from .wire import Addressing, Composed, Parsed, Wire


@dataclass(frozen=True)
class Program:
    """Everything one scenario needs to run, as the scenario kind plans it: the case, the exchange rules,
    the suite's wire, the edition, the run's parameters and its time scale."""

    case_id: str
    scenario: dict
    exchanges: tuple
    wire: Wire
    edition: str
    params: dict
    time_scale: float = 1.0
    ambiguities: dict = field(default_factory=dict)  # id -> entry of the suite's ambiguity register
    bounds: dict = field(default_factory=dict)  # name -> the suite's timing bound (seconds, and where it comes from)
    silence: tuple = ()  # the rules under which any request may go unanswered (exchanges.json ``silence``)

    def machine(self, addressing: Addressing, unique, members) -> "Machine":
        """The state machine that runs it, for a session speaking from ``addressing``; ``unique(name)`` gives
        numbers no other request of the run carries."""
        return Machine(self, addressing, unique)

    def resources(self) -> set[str]:
        """What it must not share with a scenario running at the same time: its declared resources and the
        messages it waits for (so no two scenarios wait for the same message at once). A sequence step with
        ``release`` frees them once its terminal state arrived (its replies carry the request's unique id, so
        another scenario's cannot be taken for them): only its quiet period is then left."""
        return set(self.scenario.get("resources", ())) | self.watched()

    def watched(self) -> set[str]:
        return {s[kind] for s in self.scenario["steps"] for kind in ("expect", "sequence", "silence", "alive")
                if isinstance(s.get(kind), str)}

    def exchange_for(self, message: dict) -> dict | None:
        """The exchange a sent message (values resolved) opens, if any."""
        return exchange_for(self.exchanges, self.wire, message, self.edition)


class Machine(Replies, Receiving, Judging):
    """The one public entry point: the scenario's events in, frames to send out, its findings and timeline kept."""

    def __init__(self, program: Program, addressing: Addressing, unique):
        self.program, self.addressing = program, addressing
        self.scope = Scope(dict(program.params), unique, addresses=addressing.symbols())
        self.wire, self.edition = program.wire, program.edition
        self.findings: list[Finding] = []
        self.timeline: list[dict] = []
        self.frames: list[Frame] = []
        self.sent: dict[str, Composed] = {}
        self.sent_at: dict[str, float] = {}  # send step -> when it was sent
        self.sent_from: dict[str, tuple] = {}  # send step -> (system, entity) it spoke as
        self.sends: dict[str, int] = {}  # send step -> how many times its request was sent (resends included)
        self.answers: dict[str, int] = {}  # send step -> how many replies to its request the steps took
        self.seen: set = set()  # what every step took: a byte-identical copy during a silence is the link's
        self.keys: list[tuple] = []  # (reply message, ((field, value), ...)) its requests gave replies to echo
        self.keys_seen = 0  # how many of keys the conductor has registered
        self.backlog: list[Parsed] = []  # replies to a request a later step awaits
        self.acks: dict[str, str | None] = {}  # send or setup step -> why the target refused its call, or None
        self.released = False  # its resources are free for another scenario (a released sequence ended)
        self.impairments: list[str] = []  # what the link could not show while the scenario ran
        self.suspect: list[str] = []  # lasting impairments: every failure from now on is INCONCLUSIVE
        self.t0 = 0.0
        self.index = -1
        self.step: StepState | None = None
        self.done = False
        self.error: str | None = None  # why the scenario could not run at all (a parameter, a name)

    def record(self, member: int = 0) -> dict:
        """What the scenario found, as the session hands it to the kind's judge."""
        return {"findings": [asdict(f) for f in self.findings], "timeline": self.timeline,
                "frames": [asdict(f) for f in self.frames], "error": self.error}

    # ------------------------------------------------------------------ events

    def start(self, t: float, epoch: float) -> list[Composed]:
        self.t0 = t
        return self._advance(t, epoch)

    @property
    def deadline(self) -> float | None:
        return None if self.done or self.step is None else self.step.until

    def watches(self, parsed: Parsed) -> bool:
        return parsed.message in self.program.watched()

    def deliver(self, t: float, epoch: float, parsed: Parsed, adopt: bool = False) -> list[Composed]:
        """Something arrived; ``adopt``: keep it for the byte-level checks even if no step waits for it."""
        if self.done:
            return []
        if self.watches(parsed) or adopt or parsed.problem:
            self.frames.append(Frame(len(self.frames) + 1, parsed.message, parsed.problem, parsed.clause, self._rel(t),
                                     parsed.undecided))
        owner = self._answered_step(parsed)
        if owner is not None and owner != (self.step.spec.get("reply_to") if self.step else None):
            later = owner in [s.get("reply_to") for s in self.program.scenario["steps"][self.index + 1:]]
            if later:
                self.backlog.append(parsed)
            self._log(t, "held" if later else "ignored", parsed,
                      f"a reply to the request of step {owner}" + (", kept for the step that awaits it" if later else ", too late"))
            return []
        return self._take(t, epoch, parsed)

    def _take(self, t: float, epoch: float, parsed: Parsed) -> list[Composed]:
        step = self.step
        before = step.misechoed if step is not None else None
        if step is None or not self._candidate(step, parsed):
            if step is not None and step.misechoed is not None and step.until is not None:
                if before is None and hashable(parsed.data) in self.seen:  # an earlier step's reply, copied late
                    step.misechoed = None
                    self._log(t, "duplicate", parsed, "a byte-identical copy of a datagram an earlier step took (tolerated)")
                    return []
                return self._answered_wrongly(t, epoch, step, parsed)
            if self.watches(parsed) or parsed.problem:
                self._log(t, "ignored", parsed, "not awaited by the current step" if not parsed.problem
                          else f"malformed: {parsed.problem}")
            return []
        if parsed.decoded is None:
            step.malformed += not parsed.undecided
            step.unjudged += parsed.undecided
            self._log(t, "received", parsed, f"{'not judged' if parsed.undecided else 'malformed'}: {parsed.problem}")
            if self._answers_malformed(step, parsed):
                return self._answered_malformed(t, epoch, step, parsed)
            return []
        key = hashable(parsed.data)
        if key in (self.seen if step.kind == "silence" else step.seen):  # a silence follows what earlier steps took
            self._log(t, "duplicate", parsed, "a byte-identical copy of an earlier datagram (tolerated)")
            return []
        step.seen.add(key)
        self.seen.add(key)
        if "reply_to" in step.spec:
            self.answers[step.spec["reply_to"]] = self.answers.get(step.spec["reply_to"], 0) + 1
        getattr(self, "_on_" + step.kind)(t, step, parsed)
        return self._advance(t, epoch) if self._finished(t, step) else []

    def impaired(self, t: float, why: str, lasting: bool = False) -> None:
        """The link could not show everything while the scenario ran (``why``: e.g. the kernel dropped datagrams):
        a step failing for want of a frame is then INCONCLUSIVE; ``lasting`` (another system uses the session's
        id): any failure of the scenario is."""
        if self.done:
            return
        if why not in self.impairments:
            self.impairments.append(why)
        if lasting and why not in self.suspect:
            self.suspect.append(why)
            for f in self.findings:
                if not f.passed and not f.inconclusive:
                    f.inconclusive, f.detail = True, f"{f.detail}; not judged: {why}"
        self.timeline.append({"t": self._rel(t), "event": "impaired", "note": why})

    def wake(self, t: float, epoch: float) -> list[Composed]:
        step = self.step
        if self.done or step is None or step.until is None or t < step.until:
            return []
        if step.kind == "expect" and not step.replies and step.tries < self._max_tries(step):
            step.tries += 1
            step.until = t + self._bound(step.spec["within"])
            request = self.sent[step.spec["reply_to"]]
            self.sends[step.spec["reply_to"]] += 1
            self.timeline.append({"t": self._rel(t), "event": "resent", "step": step.spec["id"],
                                  **self.wire.present(request), "note": f"try {step.tries}: no answer within the bound"})
            return [request]
        self._expire(t, step)
        return self._advance(t, epoch)

    def gone(self, t: float, epoch: float, why: str) -> list[Composed]:
        """The target is gone (``why``): each step left that waits is decided now, not at its bound, as a step that
        could not see what it waited for (a failure for want of a frame is INCONCLUSIVE, a silence is not judged)."""
        if self.done:
            return []
        self.impaired(t, why)
        out: list[Composed] = []
        while not self.done and self.step is not None and self.step.until is not None:
            self._expire(t, self.step, gone=why)
            out += self._advance(t, epoch)
        return out

    # ------------------------------------------------------------------ stepping

    def _advance(self, t: float, epoch: float) -> list[Composed]:
        out: list[Composed] = []
        while not self.done:
            failed = self._must_failed() if self.step is not None else None
            if failed:
                self._stop(t, f"a MUST step {failed}; the rest of the scenario was not run")
                break
            self.index += 1
            steps = self.program.scenario["steps"]
            if self.index >= len(steps):
                self.done, self.step = True, None
                break
            spec = steps[self.index]
            kind = next(k for k in STEP_KINDS if k in spec)
            self.step = StepState(spec, kind)
            if kind in ("send", "setup"):
                try:
                    out += [self._send(t, epoch, spec)] * spec.get("copies", 1) if kind == "send" else [self._setup(t, spec)]
                except (Unresolved, ValueError) as exc:  # a value the run gave that the message cannot carry
                    self.error = f"step {spec['id']} cannot be sent: {exc}"
                    self._stop(t, self.error)
                continue
            if kind == "accepted" and spec["accepted"] in self.acks:
                self._on_accepted(t, self.step, self.acks[spec["accepted"]])
                continue
            self.step.until = self.step.bound = t + self._bound(step_length(spec))
            held = [p for p in self.backlog if self._answered_step(p) == spec.get("reply_to")]
            if held:
                self.backlog = [p for p in self.backlog if p not in held]
                for parsed in held:
                    out += self._take(t, epoch, parsed)
            break
        return out

    def acknowledge(self, t: float, epoch: float, step_id: str, problem: str | None) -> list[Composed]:
        """The target acknowledged the call a send or setup step made (``problem``: why it refused, or None)."""
        if self.done:
            return []
        self.acks[step_id] = problem
        self.timeline.append({"t": self._rel(t), "event": "acknowledged" if problem is None else "refused",
                              "step": step_id, **({"note": problem} if problem else {})})
        kind = next((k for k in STEP_KINDS if k in self._spec(step_id)), None)
        if problem is not None and kind == "setup":
            self.error = f"the target refused to set up step {step_id}: {problem}"
            self._stop(t, self.error)
            return []
        step = self.step
        if step is not None and step.kind == "accepted" and step.spec["accepted"] == step_id:
            self._on_accepted(t, step, problem)
            return self._advance(t, epoch)
        return []

    def _spec(self, step_id: str) -> dict:
        return next(s for s in self.program.scenario["steps"] if s["id"] == step_id)

    def _setup(self, t: float, spec: dict) -> Composed:
        setup = spec["setup"]
        composed = self.wire.setup(setup["service"], resolve_plain(setup["state"], self.scope), spec["id"])
        self.timeline.append({"t": self._rel(t), "event": "setup", "step": spec["id"], **self.wire.present(composed)})
        return composed

    def _send(self, t: float, epoch: float, spec: dict) -> Composed:
        self.scope.epoch = epoch
        message = resolve_message(spec["send"], self.scope, self.wire, self.edition)
        speaker = self.addressing.speaking_as(spec.get("as"))
        composed = self.wire.compose(message, spec.get("encoding"), speaker, epoch, spec["id"], self.edition)
        self.sent[spec["id"]] = composed
        self.sent_at[spec["id"]] = t
        self.sent_from[spec["id"]] = (speaker.system, speaker.entity)
        self.sends[spec["id"]] = spec.get("copies", 1)
        self.scope.sent[spec["id"]] = composed.decoded.get("fields", {})
        exchange = self.program.exchange_for(message)
        sent = composed.decoded.get("fields", {})
        echoes = tuple((r["reply_field"], hashable(sent.get(r["request_field"])))
                       for r in (exchange or {}).get("correlation", ()) if r["kind"] == "echo")
        if echoes:
            self.keys.append((exchange["reply"], echoes))
        self.timeline.append({"t": self._rel(t), "event": "sent", "step": spec["id"], **self.wire.present(composed)})
        return composed

    def _finished(self, t: float, step: StepState) -> bool:
        if step.kind == "expect":
            return len(step.replies) >= step.spec.get("count", 1)
        if step.kind == "alive":
            return bool(step.replies)
        return False  # sequence, silence and wait end at their deadline; accepted at its acknowledgement

    def _last_wait(self, step: StepState) -> bool:
        """Whether no step after ``step`` waits for anything (only its quiet period is left)."""
        return not any(k in later for later in self.program.scenario["steps"][self.index + 1:]
                       for k in ("expect", "sequence", "silence", "alive", "accepted", "send", "setup"))

    def _must_failed(self) -> str | None:
        """Whether a MUST step failed ("failed") or could not be judged ("could not be judged")."""
        failed = [f for f in self.findings if not f.passed and f.level == "MUST"]
        if not failed:
            return None
        return "could not be judged" if all(f.inconclusive for f in failed) else "failed"

    def cannot_run(self, t: float, why: str) -> None:
        """The session could not send what the scenario sent: it stops, untested (not the node's fault)."""
        if not self.done:
            self.error = why
            self._stop(t, why)

    def _stop(self, t: float, why: str) -> None:
        self.timeline.append({"t": self._rel(t), "event": "stopped", "note": why})
        self.done, self.step = True, None

    # ------------------------------------------------------------------ answers decided at once

    def _answered_wrongly(self, t: float, epoch: float, step: StepState, parsed: Parsed) -> list[Composed]:
        """The node answered this scenario's request (to its own entity) echoing another value: the step's outcome
        is decided at once, without waiting out its bound for a reply that will never match."""
        rule, echoed = step.misechoed
        self._log(t, "received", parsed, f"the answer to this request, echoing another value ({echoed})")
        wanted = step.spec.get("expect") or step.spec.get("sequence")
        self._find(step, "", False, f"the {wanted} addressed to this request's requester echoes {echoed}",
                   rule["level"], rule["clause"])
        step.until = None
        return self._advance(t, epoch)

    def _answered_malformed(self, t: float, epoch: float, step: StepState, parsed: Parsed) -> list[Composed]:
        """The node answered this scenario's request with a frame that does not decode: the step's outcome is
        decided at once (the frame's own byte check fails it too), without waiting out its bound and retries."""
        wanted = step.spec.get("expect") or step.spec.get("sequence")
        self._find(step, "", False, f"the {wanted} addressed to this request's requester is malformed: {parsed.problem}")
        step.until = None
        return self._advance(t, epoch)

    # ------------------------------------------------------------------ helpers

    def _rel(self, t: float) -> float:
        return round(t - self.t0, 3)

    def _log(self, t: float, event: str, parsed: Parsed, note: str) -> None:
        entry = {"t": self._rel(t), "event": event, **self.wire.present(parsed), "note": note}
        if self.step is not None:
            entry["step"] = self.step.spec["id"]
        self.timeline.append(entry)
