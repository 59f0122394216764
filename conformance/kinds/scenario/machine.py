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

from .exchanges import States, exchange_for, resolved, seconds, silence_allowed, states_for, weaker
from .matchers import hashable, mismatch, same, show
from .values import Scope, Unresolved, resolve_matcher, resolve_message, resolve_plain
from .wire import Addressing, Composed, Parsed, Wire

STEP_KINDS = ("send", "setup", "expect", "sequence", "silence", "alive", "wait", "accepted")


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


@dataclass
class Finding:
    """One expectation of one step: ``check`` is ``step:<id>`` or ``step:<id>:<what>``."""

    check: str
    passed: bool
    level: str
    clause: str
    detail: str
    inconclusive: bool = False  # failed, but the session could not see everything it needed to judge


@dataclass
class Frame:
    """A frame the node sent that this scenario looked at, for the byte-level (passive) checks."""

    n: int
    message: str | None
    problem: str | None
    clause: str | None
    t: float
    undecided: bool = False  # ``problem`` says why the frame was not judged, not what it breaks


@dataclass
class _Step:
    spec: dict
    kind: str
    until: float | None = None
    tries: int = 1
    replies: list = field(default_factory=list)
    malformed: int = 0
    unjudged: int = 0  # frames of the awaited message the suite could not judge
    terminal: Parsed | None = None
    failures: dict = field(default_factory=dict)  # check -> first detail
    unmatched: str = ""  # the first reply whose echoed value was not the request's (it is not this step's)
    unmatched_count: int = 0
    misechoed: tuple | None = None  # (echo rule, what it echoed) of a reply to this scenario's entity echoing wrongly
    bound: float | None = None  # when the step's own time is up (a quiet period after a terminal state may move until)
    open_end: str | None = None  # the ambiguity id when the sequence's last state is one the seeds leave open
    readings: dict = field(default_factory=dict)  # ambiguity id -> what the node did that the seeds leave open
    silences: set = field(default_factory=set)  # the readings among them that are a request's silence
    states: tuple = ()  # (the States of its replies, or None), once worked out
    seen: set = field(default_factory=set)  # what it took, to tell the link's byte-identical copies


class Machine:
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
        self.step: _Step | None = None
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
            self.step = _Step(spec, kind)
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
            self.step.until = self.step.bound = t + self._bound(_length(spec))
            held = [p for p in self.backlog if self._answered_step(p) == spec.get("reply_to")]
            if held:
                self.backlog = [p for p in self.backlog if p not in held]
                for parsed in held:
                    out += self._take(t, epoch, parsed)
            break
        return out

    def _answered_step(self, parsed: Parsed) -> str | None:
        """The send step whose request this reply echoes (by the exchange's echo fields), if any; else, for a reply
        addressed to the session's second system, or to a requester of an exchange without echo fields, the
        latest request sent from that address that such a reply answers."""
        if parsed.decoded is None:
            return None
        to = self.wire.destination(parsed)
        by_address = None
        for step_id, composed in self.sent.items():
            exchange = self.program.exchange_for({"abbrev": composed.message, "fields": composed.decoded["fields"]})
            if not exchange or exchange["reply"] != parsed.message:
                continue
            echoes = [r for r in exchange.get("correlation", ()) if r["kind"] == "echo"]
            if echoes and all(same(parsed.fields.get(r["reply_field"]), composed.decoded["fields"].get(r["request_field"]))
                              for r in echoes):
                return step_id
            if to is not None and tuple(to) == self.sent_from[step_id] and (to[0] == self.addressing.other or not echoes):
                by_address = step_id
        return by_address

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

    def _on_accepted(self, t: float, step: _Step, problem: str | None) -> None:
        ref = step.spec["accepted"]
        self._find(step, "", problem is None, f"step {ref}'s call was accepted" if problem is None
                   else f"step {ref}'s call was refused: {problem}")

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

    def _finished(self, t: float, step: _Step) -> bool:
        if step.kind == "expect":
            return len(step.replies) >= step.spec.get("count", 1)
        if step.kind == "alive":
            return bool(step.replies)
        return False  # sequence, silence and wait end at their deadline; accepted at its acknowledgement

    def _last_wait(self, step: _Step) -> bool:
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

    # ------------------------------------------------------------------ reading replies

    def _candidate(self, step: _Step, parsed: Parsed) -> bool:
        spec = step.spec
        if step.kind == "alive":
            wanted = spec["alive"]
            if parsed.decoded is None or (wanted and parsed.message != wanted):
                return False
            return self.addressing.from_node(self.wire, parsed)
        wanted = spec.get(step.kind) if step.kind != "wait" else None
        if not isinstance(wanted, str) or parsed.message != wanted:
            return False
        if parsed.decoded is not None and not self._for_this_speaker(step, parsed):
            return False
        exchange = self._exchange(step)
        if exchange is None or parsed.decoded is None:
            return True
        if not all(any(same(parsed.fields.get(f), v) for v in resolved(self.wire, wanted, f, names, self.edition))
                   for f, names in exchange.get("reply_when", {}).items()):
            return False
        request = self.sent[step.spec["reply_to"]].decoded.get("fields", {})
        for rule in exchange["correlation"]:  # a reply that echoes another request's value is not this one's
            if rule["kind"] == "echo" and not same(parsed.fields.get(rule["reply_field"]), request.get(rule["request_field"])):
                echoed = (f"{rule['reply_field']}={show(parsed.fields.get(rule['reply_field']))}, "
                          f"the request's {rule['request_field']} was {show(request.get(rule['request_field']))}")
                if not step.unmatched:
                    step.unmatched = echoed
                step.unmatched_count += 1
                if step.misechoed is None and self._to_this_scenario(parsed):
                    step.misechoed = (rule, echoed)
                return False
        return True

    def _for_this_speaker(self, step: _Step, parsed: Parsed) -> bool:
        """Whether a frame may be for the step: not when it is addressed to one of the session's two systems and
        the step awaits the other's (a reply to the request one client sent is not the other client's); a step
        that awaits no reply takes what is addressed to the system it names (``to``), or to the session's own."""
        to = self.wire.destination(parsed)
        ours = (self.addressing.system, self.addressing.other)
        if to is None or self.addressing.other is None or to[0] not in ours:
            return True
        ref = step.spec.get("reply_to")
        wanted = self.sent_from[ref][0] if ref is not None else self.addressing.speaking_as(step.spec.get("to")).system
        return to[0] == wanted

    def _to_this_scenario(self, parsed: Parsed) -> bool:
        """Whether a frame is addressed to this scenario's own entity (no other request of the run comes from it),
        from the node: then it answers this scenario's request, whatever it echoes."""
        to = self.wire.destination(parsed)
        return (to is not None and self.addressing.entity is not None and tuple(to) in self.sent_from.values()
                and self.addressing.from_node(self.wire, parsed))

    def _states(self, step: _Step) -> States | None:
        """The states of the replies the step awaits, for the request it answers (worked out once a step)."""
        if not step.states:
            exchange = self._exchange(step)
            step.states = (None if exchange is None else states_for(
                self.wire, exchange, self.sent[step.spec["reply_to"]].decoded.get("fields", {}), self.edition),)
        return step.states[0]

    def _exchange(self, step: _Step) -> dict | None:
        ref = step.spec.get("reply_to")
        return None if ref is None else self._exchange_of(ref)

    def _exchange_of(self, send_step: str) -> dict | None:
        """The exchange the request of a send step opened, if any."""
        sent = self.sent[send_step]
        return self.program.exchange_for({"abbrev": sent.message, "fields": sent.decoded.get("fields", {})})

    def _correlate(self, step: _Step, parsed: Parsed) -> list[tuple[str, str, str, str | None]]:
        """(check, level, clause, failure or None) for each correlation rule of the step's exchange."""
        exchange = self._exchange(step)
        if exchange is None:
            return []
        out = []
        for rule in exchange["correlation"]:
            kind = rule["kind"]
            if kind == "echo":
                continue  # a reply that does not echo is set aside as another request's (``_candidate``)
            if kind == "to-requester":
                name = kind
                to, me = self.wire.destination(parsed), self.sent_from[step.spec["reply_to"]]
                bad = None if to is None or tuple(to) == me else f"addressed to {_address(to)}, the requester is {_address(me)}"
            else:
                name = kind
                bad = None if self.addressing.from_node(self.wire, parsed) else \
                    f"sent by system {self.wire.origin(parsed)[0]}, the node is {self.addressing.node}"
            out.append((name, rule["level"], rule["clause"], bad))
        return out

    def _match_fields(self, message: str, matchers: dict, parsed: Parsed) -> str | None:
        problems = []
        for path, spec in matchers.items():
            try:
                resolved = resolve_matcher(spec, message, path, self.scope, self.wire, self.edition)
            except Unresolved as exc:
                problems.append(f"{path}: {exc}")
                continue
            why = mismatch(parsed.fields.get(path), resolved, lambda v: self.wire.size_of(message, path, v), parsed.fields)
            if why:
                problems.append(f"{path} {why}")
        return "; ".join(problems) or None

    def _on_expect(self, t: float, step: _Step, parsed: Parsed) -> None:
        spec = step.spec
        step.replies.append(parsed)
        self.scope.replies[spec["id"]] = parsed.fields
        self._log(t, "received", parsed, "matched")
        if len(step.replies) < spec.get("count", 1):
            return
        tries = f" (answered on try {step.tries})" if step.tries > 1 else ""
        self._find(step, "", True, f"{spec['expect']} received after {self._rel(t) - self._started(step):.3f} s{tries}")
        for name, level, clause, bad in self._correlate(step, parsed):
            self._find(step, name, bad is None, bad or "as required", level, clause)
        if spec.get("fields"):
            bad = self._match_fields(spec["expect"], spec["fields"], parsed)
            self._find(step, "fields", bad is None, bad or "fields as expected")
        for more in spec.get("also", ()):  # checks of the same reply at a weaker level: a SHOULD, or a reading
            bad = self._match_fields(spec["expect"], more["fields"], parsed)
            if more["level"] == "INFO":
                self._read(step, more["ambiguity"], f"{more['statement']}: " + (f"no ({bad})" if bad else "yes"))
            else:
                self._find(step, more["id"], bad is None, bad or more["statement"], more["level"], more["clause"])
        self._readings(step)

    def _on_sequence(self, t: float, step: _Step, parsed: Parsed) -> None:
        spec = step.spec
        states = self._states(step)
        field_ = states.field if states else None
        value = parsed.fields.get(field_)
        name = self._state_name(spec["sequence"], field_, value)
        step.replies.append(parsed)
        for check, level, clause, bad in self._correlate(step, parsed):
            _note(step, (check, level, clause), bad)
        if spec.get("fields"):
            _note(step, ("fields", spec.get("level", "MUST"), None), self._match_fields(spec["sequence"], spec["fields"], parsed))
        if states is None:
            return
        if "not_after" in spec:
            _note(step, ("not-after", spec.get("level", "MUST"), None), self._too_late(t, step, states, value, name))
        if step.terminal is not None:
            if step.open_end is None:
                _note(step, ("after-terminal", states.level, states.clause),
                      f"{name} after the terminal state {self._terminal_name(step)}")
                self._log(t, "received", parsed, f"{name}: after the terminal state")
                return
            self._read(step, step.open_end, f"{self._terminal_name(step)} was followed by {name}: read as a delay, "
                                            "not the end of the request")
            step.terminal, step.open_end = None, None
            step.until = max(step.bound, t + self._bound(spec.get("quiet", 1.0)))  # the request goes on: its own bound
        kind = states.kind(value)
        if kind == "unknown" and states.unknown is not None:
            self._read(step, states.unknown, f"{name} is not a state the definitions name for this request")
            kind, opened = "open", states.unknown
        else:
            opened = states.open.get(hashable(value))
        if kind in ("terminal", "open"):
            step.terminal, step.open_end = parsed, opened
            step.until = t + self._bound(spec.get("quiet", 1.0))
            if kind == "open":  # the request may still go on: listen until the step's own bound, the time it is given
                step.until = max(step.bound, step.until)
            self.released = self.released or (spec.get("release", False) and self._last_wait(step))
            self._log(t, "received", parsed, f"{name}: terminal state" if kind == "terminal" else
                      f"{name}: a state that may end the request or delay it (open reading {opened})")
        elif kind == "progress":
            self._log(t, "received", parsed, f"{name}: progress state")
        else:
            _note(step, ("states", states.level, states.clause),
                  f"{name} is neither a progress nor a terminal state of {spec['sequence']} for this request")
            self._log(t, "received", parsed, f"{name}: not a state of this exchange")

    def _too_late(self, t: float, step: _Step, states: States, value, name: str) -> str | None:
        """Why a reply breaks the step's ``not_after`` (a state that may not come later than a number of seconds
        after the request, the node's own seconds: not scaled), or None."""
        rule = step.spec["not_after"]
        names = resolved(self.wire, step.spec["sequence"], states.field, rule["states"], self.edition)
        if not any(same(value, v) for v in names):
            return None
        limit = float(resolve_plain(rule["seconds"], self.scope)) + self._seconds(rule.get("tolerance", 1.0))
        after = t - self.sent_at[step.spec["reply_to"]]
        return None if after <= limit else f"{name} {after:.3f} s after the request, later than {limit:g} s"

    def _read(self, step: _Step, ambiguity: str, what: str) -> None:
        """Note what the node did where the seeds leave the reading open (the ambiguity register's ``ambiguity``)."""
        step.readings.setdefault(ambiguity, what)

    def _on_silence(self, t: float, step: _Step, parsed: Parsed) -> None:
        ref = step.spec.get("reply_to")
        awaited = any(s.get("reply_to") == ref and ("expect" in s or "sequence" in s)
                      for s in self.program.scenario["steps"][:self.index])  # else no answer at all is allowed
        if ref is not None and awaited and self.answers[ref] <= self.sends[ref]:  # the request went more than once
            self._log(t, "received", parsed, f"an answer to one of the {self.sends[ref]} times the request was sent")
            return
        if "fields" in step.spec and self._match_fields(step.spec["silence"], step.spec["fields"], parsed) is not None:
            self._log(t, "ignored", parsed, "not what the silence is about (its fields)")
            return
        step.replies.append(parsed)
        self._log(t, "received", parsed, "breaks the expected silence")

    def _on_alive(self, t: float, step: _Step, parsed: Parsed) -> None:
        step.replies.append(parsed)
        self._log(t, "received", parsed, "the node is alive")
        self._find(step, "", True, f"{parsed.message} received after {self._rel(t) - self._started(step):.3f} s")

    def _answered_wrongly(self, t: float, epoch: float, step: _Step, parsed: Parsed) -> list[Composed]:
        """The node answered this scenario's request (to its own entity) echoing another value: the step's outcome
        is decided at once, without waiting out its bound for a reply that will never match."""
        rule, echoed = step.misechoed
        self._log(t, "received", parsed, f"the answer to this request, echoing another value ({echoed})")
        wanted = step.spec.get("expect") or step.spec.get("sequence")
        self._find(step, "", False, f"the {wanted} addressed to this request's requester echoes {echoed}",
                   rule["level"], rule["clause"])
        step.until = None
        return self._advance(t, epoch)

    def _answers_malformed(self, step: _Step, parsed: Parsed) -> bool:
        """Whether a frame that does not decode is what the step awaits: of the awaited message, before any valid
        one, its header addressed to the requester of the step's request (else to this scenario's entity, or to
        the system the step names); a frame the suite could not judge is not."""
        if (step.kind not in ("expect", "sequence") or parsed.undecided or step.replies or step.until is None
                or parsed.addressed is None):
            return False
        to, ref = tuple(parsed.addressed), step.spec.get("reply_to")
        if ref is not None:
            return to == self.sent_from[ref]
        if "to" in step.spec:
            return to[0] == self.addressing.speaking_as(step.spec["to"]).system
        return to in self.sent_from.values()

    def _answered_malformed(self, t: float, epoch: float, step: _Step, parsed: Parsed) -> list[Composed]:
        """The node answered this scenario's request with a frame that does not decode: the step's outcome is
        decided at once (the frame's own byte check fails it too), without waiting out its bound and retries."""
        wanted = step.spec.get("expect") or step.spec.get("sequence")
        self._find(step, "", False, f"the {wanted} addressed to this request's requester is malformed: {parsed.problem}")
        step.until = None
        return self._advance(t, epoch)

    def _expire(self, t: float, step: _Step, gone: str | None = None) -> None:
        """The step's time is up (or, ``gone``, the target is: it is decided before its bound): judge what it
        gathered."""
        spec, kind = step.spec, step.kind
        bound = f"{self._seconds(_length(spec)):g}"
        if kind == "wait":
            pass
        elif kind == "silence" and gone is not None and not step.replies:
            self._find(step, "", False, f"{spec['silence']} not awaited for {bound} s", blind=gone)
        elif kind == "silence":
            got = len(step.replies)
            self._find(step, "", got == 0, f"nothing for {bound} s" if not got else f"{got} {spec['silence']} received")
        elif kind == "sequence":
            self._judge_sequence(step, bound)
        elif kind == "accepted":
            self._find(step, "", False, f"step {spec['accepted']}'s call was not acknowledged within {bound} s",
                       blind=gone)
        else:
            wanted = spec.get("expect") or spec.get("alive") or "a frame"
            got = len(step.replies)
            what = f"{got} of {spec.get('count', 1)} {wanted}" if got else f"no {wanted}"
            tries = f" ({step.tries} tries)" if step.tries > 1 else ""
            malformed = f"; {step.malformed} malformed frames of it" if step.malformed else ""
            refused = self.acks.get(spec.get("reply_to"))
            refused = f"; the call was refused: {refused}" if refused else ""
            what = f"{what} within {bound} s{tries}{malformed}{refused}{_unmatched(step)}"
            if got or not self._silence_allowed(step, what):
                self._find(step, "", False, what, blind=self._blind(step))
        self.timeline.append(self._timer(t, step) if gone is None else
                             {"t": self._rel(t), "event": "gone", "step": spec["id"],
                              "note": f"decided before its {bound} s bound ran out: the target is gone"})

    def _timer(self, t: float, step: _Step) -> dict:
        """The timeline entry of a step whose time is up, saying which of its bounds decided it: the time it is given
        (``within``, ``for``, ``wait``) or the quiet period after a terminal state, in seconds of the run, with the
        suite's name for it and the tries made."""
        spec = step.spec
        quiet = step.terminal is not None and step.bound is not None and step.until != step.bound
        key = "quiet" if quiet else next(k for k in ("within", "for", "wait") if k in spec)
        value = spec.get("quiet", 1.0) if quiet else spec[key]
        bound = {"of": key, "seconds": self._bound(value)} | ({"name": value} if isinstance(value, str) else {})
        tries = f", after {step.tries} tries" if step.tries > 1 else ""
        return {"t": self._rel(t), "event": "timer", "step": spec["id"], "bound": bound,
                "note": f"the step's time is up: its {key} bound, {bound['seconds']:g} s"
                        + (f" ({value})" if isinstance(value, str) else "") + f", ran out{tries}"}

    def _judge_sequence(self, step: _Step, bound) -> None:
        spec = step.spec
        if not step.replies:
            malformed = f"; {step.malformed} malformed frames of it" if step.malformed else ""
            what = f"no {spec['sequence']} within {bound} s{malformed}{_unmatched(step)}"
            if self._silence_allowed(step, what):
                return
            self._find(step, "", False, what, blind=self._blind(step))
            return
        self._find(step, "", True, f"{len(step.replies)} {spec['sequence']} received")
        states = self._states(step)
        for (check, level, clause), bad in step.failures.items():
            if check not in ("after-terminal", "states"):
                self._find(step, check, bad is None, bad or "as required", level, clause)
        if states is None:
            return
        trail = " -> ".join(self._state_name(spec["sequence"], states.field, r.fields.get(states.field))
                            for r in step.replies)
        level = weaker(spec.get("level", "MUST"), states.level)
        if step.terminal is None:
            what = f"no terminal state within {bound} s ({trail})"
            reading = self._silence_reading(step, unended=True)
            if reading is not None:  # a request a later one may have replaced: its end is not owed
                self._read(step, reading, what)
                step.silences.add(reading)
            else:
                self._find(step, "terminal", False, what, level, states.clause, blind=self._blind(step))
        else:
            if step.open_end is not None:
                self._read(step, step.open_end, f"ended in {self._terminal_name(step)}: read as the end of the request")
            bad = self._match_fields(spec["sequence"], self._terminal_matchers(step, states), step.terminal)
            self._find(step, "terminal", bad is None, bad or f"ended in {self._terminal_name(step)} ({trail})",
                       level, states.clause)
            if hashable(step.terminal.fields.get(states.field)) in states.declined and states.field not in spec.get("terminal", {}):
                self._find(step, "declined", True, f"the node declined the request: {self._terminal_name(step)}",
                           "DECLINED", states.declined_clause)
        for check in ("states", "after-terminal"):
            key = (check, states.level, states.clause)
            if key in step.failures or check == "after-terminal" and step.terminal is not None:
                bad = step.failures.get(key)
                ok = "nothing after the terminal state" if check == "after-terminal" else "every state known"
                self._find(step, check, bad is None, bad or ok, states.level, states.clause)
        self._readings(step)

    def _terminal_matchers(self, step: _Step, states: States) -> dict:
        """The fields the terminal reply must hold: the step's ``terminal``, and its ``on_state`` entry for the
        state it ended in."""
        matchers = dict(step.spec.get("terminal", {}))
        value = step.terminal.fields.get(states.field)
        for name, more in step.spec.get("on_state", {}).items():
            try:
                if same(value, self.wire.resolve(step.spec["sequence"], states.field, name, self.edition)):
                    matchers.update(more)
            except KeyError:
                continue  # a state this edition does not have
        return matchers

    def _silence_allowed(self, step: _Step, what: str) -> bool:
        """Where the register reads silence as allowed (the exchange's ``silence`` for the request, or the rules for
        every request, or the step's ``if_silent`` where it awaits no reply), the lack of a reply is noted as that
        reading, not failed (unless the session could not see everything: then it is not judged)."""
        ambiguity = self._silence_reading(step)
        if ambiguity is None:
            return False
        self._read(step, ambiguity, what)
        step.silences.add(ambiguity)
        self._readings(step)
        return True

    def _silence_reading(self, step: _Step, unended: bool = False) -> str | None:
        """The reading under which the step's request may go unanswered (``unended``: may be left without its end),
        or None; None too where the session could not see everything."""
        ambiguity = None if unended else step.spec.get("if_silent")
        exchange = self._exchange(step)
        if exchange is not None:
            ref = step.spec["reply_to"]
            request = self.sent[ref].decoded.get("fields", {})
            ambiguity = silence_allowed(self.wire, exchange, request, self.edition, self._facts(ref, exchange),
                                        self.program.silence, unended)
        if ambiguity is None or self._blind(step) is not None or self.suspect:
            return None
        return ambiguity

    def _facts(self, ref: str, exchange: dict) -> dict:
        """What the silence rules may select a request by, beyond its fields: the fields naming a system nobody
        answers for (``$nobody``), the echoed fields whose value an earlier request of the exchange carried, and
        where it was addressed ("elsewhere": neither to the node nor to anyone)."""
        spec = self._spec(ref)["send"]["fields"]
        nobody = {name for name, value in spec.items() if isinstance(value, dict) and "$nobody" in value}
        sent = self.sent[ref].decoded.get("fields", {})
        order = [s["id"] for s in self.program.scenario["steps"]]
        earlier = [self.sent[s].decoded.get("fields", {}) for s in self.sent
                   if order.index(s) < order.index(ref) and self._exchange_of(s) is exchange]
        reuses = {r["request_field"] for r in exchange.get("correlation", ()) if r["kind"] == "echo"
                  and any(same(e.get(r["request_field"]), sent.get(r["request_field"])) for e in earlier)}
        answered = {p for p in (self._answered_step(r) for r in self.backlog) if p is not None} | {
            s for s, n in self.answers.items() if n}
        later = [self.sent[s].decoded.get("fields", {}) for s in self.sent if s in answered
                 and order.index(s) > order.index(ref) and self._exchange_of(s) is exchange]
        reused = {r["request_field"] for r in exchange.get("correlation", ()) if r["kind"] == "echo"
                  and any(same(e.get(r["request_field"]), sent.get(r["request_field"])) for e in later)}
        composed = self.sent[ref]
        to = self.wire.destination(Parsed(composed.data, composed.message, composed.decoded))
        elsewhere = to is not None and to[0] not in (self.addressing.node, self.wire.anyone)
        return {"nobody": nobody, "reuses": reuses, "reused": reused, "to": "elsewhere" if elsewhere else None}

    def _readings(self, step: _Step) -> None:
        """One check per open reading the step met, always in the report: INFO, never a failure; or, for a request's
        silence where the register's entry is a SHOULD (the seeds define a reply for the case without requiring it),
        a SHOULD not met."""
        for ambiguity, what in step.readings.items():
            entry = self.program.ambiguities.get(ambiguity, {})
            reading = f": {entry['suite']}" if "suite" in entry else ""
            should = ambiguity in step.silences and entry.get("level") == "SHOULD"
            self._find(step, f"reading-{ambiguity}", not should,
                       f"{what} ({'register entry' if should else 'open reading'} {ambiguity}{reading})",
                       "SHOULD" if should else "INFO", entry.get("clause"))

    # ------------------------------------------------------------------ helpers

    def _find(self, step: _Step, what: str, passed: bool, detail: str, level: str | None = None,
              clause: str | None = None, blind: str | None = None) -> None:
        """Record a check of the step; ``blind``: why a failure for want of a frame cannot be judged."""
        spec = step.spec
        check = f"step:{spec['id']}" + (f":{what}" if what else "")
        blind = "; ".join(self.suspect) or blind
        inconclusive = not passed and blind is not None
        self.findings.append(Finding(check, passed, level or spec.get("level", "MUST"),
                                     clause or spec.get("clause") or self.program.scenario["clause"],
                                     f"{detail}; not judged: {blind}" if inconclusive else detail, inconclusive))

    def _blind(self, step: _Step) -> str | None:
        """Why the session may have missed what the step waited for, or None."""
        why = list(self.impairments)
        if step.unjudged:
            why.append(f"{step.unjudged} frame(s) of it could not be judged")
        return "; ".join(why) or None

    def _seconds(self, value) -> float:
        """A bound as data gives it (seconds, or the name of one of the suite's bounds), in seconds."""
        return seconds(value, self.program.bounds)

    def _bound(self, value) -> float:
        """A bound in seconds of the run (scaled by --time-scale)."""
        return self._seconds(value) * self.program.time_scale

    def _max_tries(self, step: _Step) -> int:
        exchange = self._exchange(step)
        return step.spec.get("tries", 3) if exchange is not None and exchange.get("idempotent") else 1

    def _started(self, step: _Step) -> float:
        return self._rel(step.until) - self._bound(step.spec.get("within", 0)) if step.until is not None else 0.0

    def _rel(self, t: float) -> float:
        return round(t - self.t0, 3)

    def _log(self, t: float, event: str, parsed: Parsed, note: str) -> None:
        entry = {"t": self._rel(t), "event": event, **self.wire.present(parsed), "note": note}
        if self.step is not None:
            entry["step"] = self.step.spec["id"]
        self.timeline.append(entry)

    def _state_name(self, message: str, path: str | None, value) -> str:
        if path is None:
            return message
        named = self.wire.present(Parsed(None, message, {"fields": {path: value}}))
        return f"{path}={named.get('fields', {}).get(path, value)}"

    def _terminal_name(self, step: _Step) -> str:
        field_ = self._states(step).field
        return self._state_name(step.spec["sequence"], field_, step.terminal.fields.get(field_))


def _length(spec: dict):
    """How long a waiting step lasts, in seconds of the scenario (before --time-scale)."""
    return spec.get("within", spec.get("for", spec.get("wait")))


def _unmatched(step: _Step) -> str:
    """What a failed step says of the replies it set aside because they echo another request."""
    if not step.unmatched_count:
        return ""
    return (f"; {step.unmatched_count} {step.spec.get('expect') or step.spec.get('sequence')} set aside as another "
            f"request's (e.g. {step.unmatched})")


def _note(step: _Step, key: tuple, bad: str | None) -> None:
    """Keep the first failure of a check over all the replies of a sequence (None: passed so far)."""
    if step.failures.get(key) is None:
        step.failures[key] = bad


def _address(pair) -> str:
    system, entity = pair
    return f"{system}/{entity}"
