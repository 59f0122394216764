"""A session that runs scenarios against a live target over datagrams: the I/O loop around the sans-IO
scenario conductor and the suite's manners on the link (e.g. IMC's announce and heartbeat).

The transport does the I/O and owns the clock: real UDP on a monotonic clock, or an in-memory link on
virtual time (tests, benchmark). Nothing here knows a protocol: the suite's ``Peer`` says what the session
sends on its own and when the target has shown itself, its ``Wire`` parses what arrives.
"""

from __future__ import annotations

from typing import Iterable, Iterator, Protocol

from ..capture.outside import Outside
from ..capture.recording import DAMAGED, OWN, RECEIVED
from ..core.results import Incident
from ..core.session import Answer, Job
from ..kinds.scenario import Addressing, Conductor


class Transport(Protocol):
    target: tuple  # the target's address
    address: tuple  # the session's own

    def now(self) -> float: ...

    def epoch(self, t: float) -> float:
        """Seconds since 1970 at clock time t."""

    def send(self, data: bytes, address=None) -> str | None:
        """To the target (``address`` None) or to another port of its host (discovery); why it could not be
        sent, or None."""

    def receive(self, until: float) -> tuple[float, bytes, tuple] | None:
        """The next datagram from the target's host, when it arrived and where from, or None once ``until`` has
        passed."""

    def drops(self, poll: bool = False) -> int:
        """(optional) Datagrams lost before the session could read them, so far (``poll``: ask now)."""

    def close(self) -> None: ...


class Peer(Protocol):
    system: int | None  # the session's own id on the link
    other: int | None  # its second id (a second client), or None
    node: int | None  # the target's id, given or learned
    ready: bool  # the target has shown itself (or was given)

    @property
    def deadline(self) -> float | None: ...

    def start(self, t: float) -> list[tuple[object, bytes]]: ...

    def due(self, t: float) -> list[tuple[object, bytes]]: ...

    def observe(self, t: float, parsed, from_target: bool) -> None:
        """Something arrived (``from_target``: from the target's own address, not another port of its host)."""

    def accepts(self, parsed) -> bool:
        """Whether something that arrived is for the session (by its header), so the scenarios see it."""

    def own(self, parsed) -> bool:
        """Whether something that arrived was sent as the session (its own frames echoed back, or another
        system's using its id): never the target's."""

    def impostor(self, parsed) -> str | None:
        """Why something that arrived shows another system using the session's identity on the link, or None."""

    def gone(self, t: float) -> str | None:
        """(optional) Why the target is taken for gone at ``t`` (liveness: it stopped sending anything), or None."""


class DatagramSession:
    stderr = ""

    def __init__(self, transport: Transport, peer: Peer, wire, hello: dict, startup: float, restart=None,
                 recorder=None, first_unique: int = 1000):
        """``startup``: seconds to wait for the target to show itself before every scenario is INCONCLUSIVE;
        ``restart()``: restarts the target (None, or why it could not), for the robustness phase to bisect;
        ``recorder.record(epoch, src, dst, data, comment)`` is told of every datagram sent and received;
        ``first_unique``: where the run's request ids and sequence numbers start (a run of its own, apart from
        another run's on the same node)."""
        self.transport, self.peer, self.wire, self._hello, self.startup = transport, peer, wire, hello, startup
        self.first_unique = first_unique
        self.restart, self.recorder = restart, recorder
        self.name = hello["implementation"]
        self.heard = 0  # valid frames from the target (never the session's own)
        self.unsent: list[str] = []  # why the session's own datagrams (announce, heartbeat) could not be sent
        self.drops = 0  # datagrams the transport lost before the session read them
        self.impostors: list[str] = []  # evidence that another system uses the session's identity
        self.gone: str | None = None  # why the target is taken for gone now (the peer's liveness), or None
        self.incidents: list[Incident] = []  # each time it was, with the cases decided then
        self.conductor: Conductor | None = None
        self.outside = Outside()  # sound frames of messages outside the suite (a vehicle's other traffic), counted

    def hello(self) -> dict:
        return self._hello

    def run(self, jobs: Iterable[Job]) -> Iterator[tuple[Job, Answer]]:
        jobs = list(jobs)
        if not jobs:
            return
        if not self._introduce():
            why = (f"inconclusive: no valid frame from {self.name} within {self.startup:g} s (is it running, and does "
                   "it answer peers that announce themselves? --dst starts at once)")
            for job in jobs:
                yield job, Answer("inconclusive", reason=why)
            return
        conductor = self.conductor = Conductor(jobs, lambda job: job.request.params["program"],
                                               Addressing(self.peer.system, None, self.peer.node,
                                                          getattr(self.peer, "other", None),
                                                          getattr(self.peer, "stranger", None),
                                                          getattr(self.peer, "late", None)), self.transport.epoch,
                                               first_unique=self.first_unique)
        self.began = self.transport.now()
        self._transmit(conductor.start(self.began))
        while True:
            while conductor.finished:
                job, record = conductor.finished.pop(0)
                if self.incidents and any(e.get("event") == "gone" for e in record.get("timeline", ())):
                    self.incidents[-1].cases.append(job.case_id)
                yield job, Answer("ok", message=record)
            if conductor.done:
                return
            if conductor.restart_wanted:
                self._transmit(conductor.restarted(self.transport.now(), self._restart()))
                continue
            deadline = min((x for x in (conductor.deadline, self.peer.deadline) if x is not None),
                           default=self.transport.now())
            self._step(deadline, conductor)

    def _introduce(self) -> bool:
        """Introduce the session to the target and wait (bounded) until it shows itself; whether it did."""
        t = self.transport.now()
        self._send(self.peer.start(t))
        bound = t + self.startup
        while not self.peer.ready and t < bound:
            self._step(min(bound, self.peer.deadline or bound), None)
            t = self.transport.now()
        return self.peer.ready

    def _restart(self) -> str | None:
        """Restart the target and introduce the session again; why that failed, or None."""
        if self.restart is None:
            return "the session cannot restart the target"
        problem = self.restart()
        if problem is None and not self._introduce():
            problem = f"no valid frame from {self.name} within {self.startup:g} s of the restart"
        return problem

    def _step(self, until: float, conductor: Conductor | None) -> None:
        got = self.transport.receive(until)
        t = self.transport.now()
        if got is not None:
            arrived, data, source = got
            self._record(arrived, tuple(source), tuple(self.transport.address[:2]), data, RECEIVED)
            self._received(arrived, data, source, conductor)
        if conductor is not None and conductor.deadline is not None and conductor.deadline <= t:
            self._losses(t, conductor, poll=True)  # before a step is judged, whatever the kernel dropped since
            if not self.heard:
                conductor.impaired(t, f"nothing has come from {self.name} yet (is the address right?)")
        if conductor is not None:
            self._liveness(t, conductor)
            self._transmit(conductor.wake(t))
        self._send(self.peer.due(t))

    def _received(self, arrived: float, data: bytes, source: tuple, conductor: Conductor | None) -> None:
        """Parse a datagram and hand it to the peer and the scenarios; a sound frame of a message outside the suite
        (a vehicle's other traffic) is counted, its framing checked, and judged no further."""
        parsed = self.wire.parse(data)
        self._losses(arrived, conductor, poll=False)
        if parsed.outside is not None:
            self.outside.add(parsed.outside, parsed.undefined)
            return
        impostor = self.peer.impostor(parsed)
        if impostor is not None:
            self._impostor(arrived, conductor, impostor)
        if parsed.decoded is not None and not self.peer.own(parsed):
            self.heard += 1
        self.peer.observe(arrived, parsed, tuple(source) == tuple(self.transport.target[:2]))
        if conductor is not None and self.peer.accepts(parsed):
            self._transmit(conductor.deliver(arrived, parsed))
            for why in conductor.impostors:
                if why not in self.impostors:
                    self.impostors.append(why)

    def _liveness(self, t: float, conductor: Conductor) -> None:
        """Tell the scenarios when the target is gone (the peer says why), so that what waits on it is decided then
        instead of at each bound; and when it is back."""
        gone = getattr(self.peer, "gone", None)
        why = gone(t) if gone is not None else None
        if (why is None) == (self.gone is None):
            return
        self.gone = why
        if why is not None:
            self.incidents.append(Incident("gone", f"at {t - self.began:.1f} s of the run, {why}", []))
        self._transmit(conductor.absent(t, why))

    def _losses(self, t: float, conductor: Conductor | None, poll: bool) -> None:
        """Tell the scenarios of datagrams the transport lost since it last said."""
        count = getattr(self.transport, "drops", None)
        total = count(poll) if count is not None else 0
        if total > self.drops:
            lost, self.drops = total - self.drops, total
            if conductor is not None:
                conductor.impaired(t, f"the kernel dropped {lost} datagram(s) before the session could read them")

    def _impostor(self, t: float, conductor: Conductor | None, why: str) -> None:
        """Another system uses the session's identity: for the rest of the run, a missing reply may be its."""
        if why not in self.impostors:
            self.impostors.append(why)
        if conductor is not None:
            conductor.impaired(t, why, lasting=True)

    def _transmit(self, outgoing) -> None:
        for item in list(outgoing):
            comment = f"{item.job.case_id} {item.composed.extra.get('step', '')}".rstrip()
            comment += f" {DAMAGED}" if item.composed.extra.get("damaged") else ""
            self._record(self.transport.now(), tuple(self.transport.address[:2]), tuple(self.transport.target[:2]),
                         item.composed.data, comment)
            why = self.transport.send(item.composed.data)
            if why:  # the scenario cannot go on; the node is not to blame
                self._transmit(self.conductor.undeliverable(self.transport.now(), item.job, why))
            spoke = getattr(self.peer, "spoke", None)  # a system the session speaks as may now be announced
            if spoke is not None and not why:
                self._send(spoke(self.transport.now(), item.composed.decoded))

    def _send(self, datagrams) -> None:
        for address, data in datagrams:
            self._record(self.transport.now(), tuple(self.transport.address[:2]),
                         tuple((address or self.transport.target)[:2]), data, OWN)
            why = self.transport.send(data, address)
            if why and why not in self.unsent:
                self.unsent.append(why)

    def _record(self, t: float, src: tuple, dst: tuple, data: bytes, comment: str) -> None:
        if self.recorder is not None:
            self.recorder.record(self.transport.epoch(t), src, dst, data, comment)

    @property
    def notes(self) -> list[str]:
        """What the report should say about the link."""
        out = list(getattr(self.peer, "notes", [])) + list(getattr(self.transport, "notes", []))
        out += [f"the session's own announce or heartbeat: {why}" for why in self.unsent[:3]]
        out += self.outside.notes(getattr(self.wire, "outside_judged", "judged no further"))
        if not self.heard:
            out.append(f"no valid frame ever came from {self.name}: check the address and port")
        if self.drops:
            out.append(f"{self.drops} datagrams were dropped by the kernel before the session could read them (a flood, "
                       "or a receive buffer too small): a step that failed for want of a frame is INCONCLUSIVE")
        out += [f"another system may be using the session's identity: {why} (--src sets another id); a step that "
                "failed for want of a frame is INCONCLUSIVE" for why in self.impostors[:3]]
        return out

    def close(self) -> None:
        self.transport.close()
