"""Which step of a scenario a frame from the node answers: the exchange rules' matching and correlation of
replies, and the states a sequence's replies pass through."""

from __future__ import annotations

from .exchanges import States, resolved, states_for
from .matchers import mismatch, same, show
from .records import StepState
from .values import Unresolved, resolve_matcher
from .wire import Parsed


class Replies:
    """The scenario machine's reading of replies (a mixin of ``Machine``)."""

    def _answered_step(self, parsed: Parsed) -> str | None:
        """The send step whose request this reply echoes (by the exchange's echo fields; of requests echoing the same
        values, the one the current step awaits), if any; else, for a reply
        addressed to the session's second system, or to a requester of an exchange without echo fields, the
        latest request sent from that address that such a reply answers."""
        if parsed.decoded is None:
            return None
        to = self.wire.destination(parsed)
        by_address = None
        awaited = self.step.spec.get("reply_to") if self.step is not None else None
        order = sorted(self.sent, key=lambda s: s != awaited)  # requests echoing the same values: the awaited one's
        for step_id in order:
            composed = self.sent[step_id]
            exchange = self.program.exchange_for({"abbrev": composed.message, "fields": composed.decoded["fields"]})
            echoes = [r for r in exchange.get("correlation", ()) if r["kind"] == "echo"] if exchange else []
            if (echoes and exchange["reply"] == parsed.message and all(
                    same(parsed.fields.get(r["reply_field"]), composed.decoded["fields"].get(r["request_field"]))
                    for r in echoes)):
                return step_id
        for step_id, composed in self.sent.items():
            exchange = self.program.exchange_for({"abbrev": composed.message, "fields": composed.decoded["fields"]})
            if not exchange or exchange["reply"] != parsed.message:
                continue
            echoes = [r for r in exchange.get("correlation", ()) if r["kind"] == "echo"]
            if to is not None and tuple(to) == self.sent_from[step_id] and (to[0] == self.addressing.other or not echoes):
                by_address = step_id
        return by_address

    def _candidate(self, step: StepState, parsed: Parsed) -> bool:
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

    def _for_this_speaker(self, step: StepState, parsed: Parsed) -> bool:
        """Whether a frame may be for the step: not when it is addressed to one of the session's systems and
        the step awaits another's (a reply to the request one client sent is not the other client's); a step
        that awaits no reply takes what is addressed to the system it names (``to``; "session": the session's own system
        and not anyone, "anyone": anyone and not the session's own), or to the session's own or anyone."""
        to = self.wire.destination(parsed)
        if step.spec.get("to") in ("session", "anyone"):  # the session's own system itself, or anyone (told apart)
            return to is not None and to[0] == self._addressee(step.spec["to"])
        ours = (self.addressing.system, self.addressing.other, self.addressing.late)
        if to is None or self.addressing.other is None or to[0] not in ours:
            return True
        ref = step.spec.get("reply_to")
        wanted = self.sent_from[ref][0] if ref is not None else self.addressing.speaking_as(step.spec.get("to")).system
        return to[0] == wanted

    def _addressee(self, to: str) -> int | None:
        """The system a step's ``to`` names: the session's second (other), the late one, the session's own (session)
        or the destination meaning any system (anyone)."""
        if to == "anyone":
            return self.wire.anyone
        return self.addressing.speaking_as(None if to == "session" else to).system

    def _to_this_scenario(self, parsed: Parsed) -> bool:
        """Whether a frame is addressed to this scenario's own entity (no other request of the run comes from it),
        from the node: then it answers this scenario's request, whatever it echoes."""
        to = self.wire.destination(parsed)
        return (to is not None and self.addressing.entity is not None and tuple(to) in self.sent_from.values()
                and self.addressing.from_node(self.wire, parsed))

    def _answers_malformed(self, step: StepState, parsed: Parsed) -> bool:
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
            return to[0] == self._addressee(step.spec["to"])
        return to in self.sent_from.values()

    def _states(self, step: StepState) -> States | None:
        """The states of the replies the step awaits, for the request it answers (worked out once a step)."""
        if not step.states:
            exchange = self._exchange(step)
            step.states = (None if exchange is None else states_for(
                self.wire, exchange, self.sent[step.spec["reply_to"]].decoded.get("fields", {}), self.edition),)
        return step.states[0]

    def _exchange(self, step: StepState) -> dict | None:
        ref = step.spec.get("reply_to")
        return None if ref is None else self._exchange_of(ref)

    def _exchange_of(self, send_step: str) -> dict | None:
        """The exchange the request of a send step opened, if any."""
        sent = self.sent[send_step]
        return self.program.exchange_for({"abbrev": sent.message, "fields": sent.decoded.get("fields", {})})

    def _correlate(self, step: StepState, parsed: Parsed) -> list[tuple[str, str, str, str | None]]:
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

    def _state_name(self, message: str, path: str | None, value) -> str:
        if path is None:
            return message
        named = self.wire.present(Parsed(None, message, {"fields": {path: value}}))
        return f"{path}={named.get('fields', {}).get(path, value)}"

    def _terminal_name(self, step: StepState) -> str:
        field_ = self._states(step).field
        return self._state_name(step.spec["sequence"], field_, step.terminal.fields.get(field_))


def _address(pair) -> str:
    system, entity = pair
    return f"{system}/{entity}"
