"""Judging what a scenario step gathered once its time is up (or the target is gone): the bounds and timers, a
sequence's states, a silence, the open readings the register allows, and the findings they make."""

from __future__ import annotations

from .exchanges import States, seconds, silence_allowed, weaker
from .matchers import hashable, same
from .records import Finding, StepState, step_length
from .wire import Parsed


class Judging:
    """The scenario machine's judging of steps (a mixin of ``Machine``)."""

    def _expire(self, t: float, step: StepState, gone: str | None = None) -> None:
        """The step's time is up (or, ``gone``, the target is: it is decided before its bound): judge what it
        gathered."""
        spec, kind = step.spec, step.kind
        bound = f"{self._seconds(step_length(spec)):g}"
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

    def _timer(self, t: float, step: StepState) -> dict:
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

    def _judge_sequence(self, step: StepState, bound) -> None:
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

    def _terminal_matchers(self, step: StepState, states: States) -> dict:
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

    def _silence_allowed(self, step: StepState, what: str) -> bool:
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

    def _silence_reading(self, step: StepState, unended: bool = False) -> str | None:
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
        answers for (``$nobody``), the echoed fields whose value an earlier request of the exchange carried,
        where it was addressed ("elsewhere": neither to the node nor to anyone), the fields of the earlier
        messages of its kind sent from the same system (``earlier``), and whether it was sent in copies of which one
        was answered already (``copied``)."""
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
        earlier_kind = [self.sent[s].decoded.get("fields", {}) for s in self.sent if order.index(s) < order.index(ref)
                        and self.sent[s].message == composed.message and self.sent_from[s] == self.sent_from[ref]]
        copied = self._spec(ref).get("copies", 1) > 1 and self.answers.get(ref, 0) > 0
        return {"nobody": nobody, "reuses": reuses, "reused": reused, "to": "elsewhere" if elsewhere else None,
                "earlier": earlier_kind, "copied": copied}

    def _readings(self, step: StepState) -> None:
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

    def _read(self, step: StepState, ambiguity: str, what: str) -> None:
        """Note what the node did where the seeds leave the reading open (the ambiguity register's ``ambiguity``)."""
        step.readings.setdefault(ambiguity, what)

    def _find(self, step: StepState, what: str, passed: bool, detail: str, level: str | None = None,
              clause: str | None = None, blind: str | None = None) -> None:
        """Record a check of the step; ``blind``: why a failure for want of a frame cannot be judged."""
        spec = step.spec
        check = f"step:{spec['id']}" + (f":{what}" if what else "")
        blind = "; ".join(self.suspect) or blind
        inconclusive = not passed and blind is not None
        self.findings.append(Finding(check, passed, level or spec.get("level", "MUST"),
                                     clause or spec.get("clause") or self.program.scenario["clause"],
                                     f"{detail}; not judged: {blind}" if inconclusive else detail, inconclusive))

    def _blind(self, step: StepState) -> str | None:
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

    def _max_tries(self, step: StepState) -> int:
        exchange = self._exchange(step)
        return step.spec.get("tries", 3) if exchange is not None and exchange.get("idempotent") else 1

    def _started(self, step: StepState) -> float:
        return self._rel(step.until) - self._bound(step.spec.get("within", 0)) if step.until is not None else 0.0


def _unmatched(step: StepState) -> str:
    """What a failed step says of the replies it set aside because they echo another request."""
    if not step.unmatched_count:
        return ""
    return (f"; {step.unmatched_count} {step.spec.get('expect') or step.spec.get('sequence')} set aside as another "
            f"request's (e.g. {step.unmatched})")
