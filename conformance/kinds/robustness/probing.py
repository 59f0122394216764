"""The robustness phase's probes: one round asks every probe at once and waits for the replies that show each
request kind is still served, a probe's reply known by the values it echoes or by its addressee, the probe's own
entity; its wait grows with the requests of its kind just replayed, which a node may queue."""

from __future__ import annotations

from ..scenario.exchanges import exchange_for, seconds
from ..scenario.matchers import hashable, same
from ..scenario.values import Scope, Unresolved, resolve_message
from ..scenario.wire import Parsed
from .script import Frame, Probe, Send, Wait


class Probing:
    """The phase machine's rounds of probes (a mixin of ``PhaseMachine``)."""

    def _round(self, probes: list[Probe], when: str, patience: float = 0.0):
        """Ask every probe at once (and again, up to each probe's tries, and for ``patience`` seconds: a node just
        restarted may take a while to serve again) and wait for the replies that show each request kind is served;
        the probes that got none."""
        waiting, until, attempt = {id(p): p for p in probes}, self.now + patience, 0
        tries = dict.fromkeys(waiting, 0)
        queues = {id(p): self._queue(p.program.case["probe"], self.replayed) for p in probes}
        self.replayed = []
        impaired = len(self.impairments)
        while waiting:
            attempt += 1
            asked = {}
            for probe in waiting.values():
                spec = probe.program.case["probe"]
                if attempt > spec.get("tries", 2) and self.now >= until:
                    continue
                tries[id(probe)] += 1
                accepts, composed = self._ask(probe, spec)
                if composed is not None:
                    yield Send(composed)
                wait = self._bound(spec, queues[id(probe)] if attempt == 1 else None)
                asked[id(probe)] = (probe, accepts, self.now + self._scaled(wait))
            if not asked:
                break
            while asked:
                got = yield Wait(min(d for _, _, d in asked.values()),
                                  lambda parsed: any(a(parsed) for _, a, _ in asked.values()))
                for key, (probe, accepts, deadline) in list(asked.items()):
                    if got is not None and accepts(got):
                        self._log("probe", f"{when}: {got.message} received" + (f" (try {attempt})" if attempt > 1 else ""),
                                  probe)
                        del asked[key], waiting[key]
                        got = None
                    elif deadline <= self.now:
                        del asked[key]
        blind = "; ".join(dict.fromkeys(self.impairments[impaired:]))
        for key, probe in waiting.items():
            spec = probe.program.case["probe"]
            self._log("probe", f"{when}: no {spec.get('expect') or spec.get('alive')} within "
                               f"{self._said(spec, queues[key])} ({tries[key]} tries)"
                      + (f"; not judged: {blind}" if blind else ""), probe)
            if blind:
                probe.blind = probe.blind or f"{when}: {blind}"
        return [] if blind else list(waiting.values())

    def _queue(self, spec: dict, frames: list[Frame]) -> int:
        """How many of the frames just replayed are requests of the probe's own exchange, which a node may queue
        and work off one at a time before it answers the probe (the probe's ``queued`` bound each); 0 for a probe
        without one."""
        if "queued" not in spec or "send" not in spec:
            return 0
        wanted = self._exchange_of(spec)
        count = 0
        for frame in frames:
            key = frame.data
            if key not in self.requests_in:
                parsed = self.wire.parse(frame.data)
                exchange = None if parsed.decoded is None else exchange_for(
                    self.phase.exchanges, self.wire, {"abbrev": parsed.message, "fields": parsed.fields}, self.phase.edition)
                self.requests_in[key] = exchange and exchange["id"]
            count += wanted is not None and self.requests_in[key] == wanted
        return count

    def _exchange_of(self, spec: dict) -> str | None:
        scope = Scope(dict(self.phase.params), lambda name: 0, self.epoch, addresses=self.addressing.symbols())
        try:
            message = resolve_message(spec["send"], scope, self.wire, self.phase.edition)
        except Unresolved:
            return None
        exchange = exchange_for(self.phase.exchanges, self.wire, message, self.phase.edition)
        return exchange and exchange["id"]

    def _bound(self, spec: dict, queued: int | None) -> float:
        """A probe's wait, in unscaled seconds: its own bound, and on its first try its ``queued`` bound for each
        request of its kind the node may still be working off."""
        own = seconds(spec["within"], self.phase.bounds)
        return own + queued * seconds(spec["queued"], self.phase.bounds) if queued else own

    def _said(self, spec: dict, queued: int) -> str:
        own = seconds(spec["within"], self.phase.bounds)
        if not queued:
            return f"{own:g} s"
        each = seconds(spec["queued"], self.phase.bounds)
        return (f"{own + queued * each:g} s ({own:g} s, and {each:g} s for each of the {queued} "
                f"request{'s' if queued != 1 else ''} of its kind just replayed, which a node may queue: bound "
                f"{spec['queued']})")

    def _ask(self, probe: Probe, spec: dict):
        """(what accepts the reply, the request to send or None) for one try of a probe."""
        if "alive" in spec:
            wanted = spec["alive"]
            return (lambda p: (wanted is None or p.message == wanted) and self.addressing.from_node(self.wire, p)), None
        scope = Scope(dict(self.phase.params), self.unique, self.epoch,
                      addresses=self.addressing.symbols())
        try:
            message = resolve_message(spec["send"], scope, self.wire, self.phase.edition)
            composed = self.wire.compose(message, spec.get("encoding"), self.addressing, self.epoch, "probe",
                                         self.phase.edition)
        except (Unresolved, ValueError) as exc:
            probe.error = f"the probe cannot be sent: {exc}"
            return (lambda p: False), None
        exchange = exchange_for(self.phase.exchanges, self.wire, message, self.phase.edition)
        echoes = [(r["reply_field"], composed.decoded["fields"].get(r["request_field"]))
                  for r in (exchange or {}).get("correlation", ()) if r["kind"] == "echo"]
        if echoes:
            self.keys.append((spec["expect"], tuple((f, hashable(v)) for f, v in echoes)))
        me = (self.addressing.system, self.addressing.entity)

        def accepts(p: Parsed) -> bool:
            if p.message != spec["expect"] or not self.addressing.from_node(self.wire, p):
                return False
            if echoes:
                return all(same(p.fields.get(f), v) for f, v in echoes)
            return tuple(self.wire.destination(p) or ()) == me
        return accepts, composed
