"""A console and a vehicle talking through the relay on virtual time: the reference node as the vehicle, the suite's
peer logic (ImcPeer: announces, heart-beats) asking queries as the console, every datagram moved by this loop."""

from __future__ import annotations

import itertools

from imc_conformance.capture.judge import CaptureJudge, Selection
from imc_conformance.relay.core import SIDES, Relay, merged
from imc_conformance.relay.impairment import Impairment, Link
from imc_conformance.suites.imc import load
from imc_conformance.suites.imc.node import ReferenceNode
from imc_conformance.suites.imc.peer import ImcPeer

CONSOLE, VEHICLE = ("127.0.0.1", 6001), ("127.0.0.1", 6002)
FACING = {"console": ("127.0.0.1", 6010), "vehicle": ("127.0.0.1", 6011)}  # the relay's sockets
EPOCH = 1_700_000_000.0
QUERIES = (("AcousticSystemsQuery", {}), ("LblConfig", {"op": 1, "beacons": []}),
           ("HistoricDataQuery", {"type": 1, "max_size": 1000, "data": None}))
SUITE = load()
RANGE_OP = next(e.value for e in SUITE.defs.by_abbrev["AcousticOperation"].fields[0].enum_values if e.abbrev == "RANGE")
RANGES = (("AcousticOperation", {"op": RANGE_OP, "system": "imc-peer-1", "range": 0.0, "msg": None}),)  # stateful


class Console:
    """The suite's peer logic as a console: every ``every`` seconds a query (in turn from its two systems), resent
    after ``retry`` seconds without its reply, up to ``tries`` times in all (``tries=1``: never resent)."""

    def __init__(self, tries: int = 4, every: float = 3.0, retry: float = 5.0, queries=QUERIES):
        defs = SUITE.defs
        self.defs, self.tries, self.every, self.retry, self.queries = defs, tries, every, retry, queries
        self.peer = ImcPeer(defs, system=0x4C10, node=None, service="imc+udp://127.0.0.1:6001/", host=CONSOLE[0],
                            epoch=lambda t: EPOCH + t)
        self.started = False
        self.next_query = 2.0
        self.count = itertools.count()
        self.waiting: dict[int, list] = {}  # query number -> [next resend time, tries left, frame fields]
        self.answered = 0

    @property
    def deadline(self) -> float:
        times = [self.next_query, *(w[0] for w in self.waiting.values())]
        return min(times + ([self.peer.deadline] if self.peer.deadline is not None else [0.0]))

    def receive(self, t: float, data: bytes) -> None:
        from imc_conformance.suites.imc import codec
        try:
            message = codec.decode(self.defs, data)
        except ValueError:
            return
        reply = {"AcousticSystems": "AcousticSystemsQuery", "LblConfig": "LblConfig", "HistoricDataQuery": "HistoricDataQuery"}
        if message["header"]["src"] in (self.peer.system, self.peer.other):
            return
        if self.peer.node is None:
            self.peer.node = message["header"]["src"]
        asked = reply.get(message["abbrev"])
        if asked is None or message["fields"].get("op", 2) != 2 or message["fields"].get("type", 2) != 2:
            return
        for n, (_, _, abbrev, fields, _) in list(self.waiting.items()):
            if abbrev == asked and fields.get("req_id") == message["fields"].get("req_id"):
                del self.waiting[n]
                self.answered += 1
                return

    def due(self, t: float) -> list[bytes]:
        out = []
        if not self.started:
            self.started = True
            out += [frame for where, frame in self.peer.start(t) if where is None]
        out += [frame for where, frame in self.peer.due(t) if where is None]
        if t >= self.next_query and self.peer.node is not None:
            self.next_query = t + self.every
            n = next(self.count)
            abbrev, fields = self.queries[n % len(self.queries)]
            fields = dict(fields, req_id=n) if abbrev == "HistoricDataQuery" else fields
            src = self.peer.system if n % 2 == 0 else self.peer.other
            self.waiting[n] = [t + self.retry, self.tries - 1, abbrev, fields, src]
            out.append(self._query(t, abbrev, fields, src))
        elif t >= self.next_query:
            self.next_query = t + self.every
        for n, w in list(self.waiting.items()):
            if t >= w[0]:
                if w[1] <= 0:
                    del self.waiting[n]
                    continue
                w[0], w[1] = t + self.retry, w[1] - 1
                out.append(self._query(t, w[2], w[3], w[4]))
        return out

    def _query(self, t: float, abbrev: str, fields: dict, src: int) -> bytes:
        from imc_conformance.suites.imc import codec
        header = {"timestamp": EPOCH + t, "src": src, "src_ent": 0, "dst": self.peer.node, "dst_ent": 0xFF}
        return codec.encode(self.defs, {"abbrev": abbrev, "header": header, "fields": fields}, "le")


def judge() -> CaptureJudge:
    rules = SUITE.capture_rules()
    ports = frozenset(p for _, p in (CONSOLE, VEHICLE, *FACING.values()))
    return CaptureJudge(SUITE.name, rules, SUITE.editions[0], Selection(ports=ports))


def simulate(seconds: float, impair: dict | None = None, seed: int = 0, console: Console | None = None,
             broken: str | None = None, log: list | None = None, record=None, after: float = 0.0):
    """Run a console and a reference node through the relay for ``seconds`` of virtual time; the relay, the
    console and the merged result. ``log`` collects (time, side, 'sent' or 'received', data, delivered intact);
    ``after``: seconds the vehicle takes before each datagram it sends (a slow vehicle)."""
    impair = impair or {}
    console = console or Console()
    links = {side: Link(impair.get(side, Impairment()), seed, side) for side in SIDES}
    relay = Relay({side: judge() for side in SIDES}, links, FACING, {"console": None, "vehicle": VEHICLE},
                  record=record, **SUITE.relay_hooks())
    node = ReferenceNode(SUITE.defs, SUITE.behaviour, edition=SUITE.editions[0], address=VEHICLE, broken=broken,
                         epoch0=EPOCH)
    t = 0.0
    outbox: list[tuple[float, bytes]] = []  # what the slow vehicle has yet to send
    while t <= seconds:
        for data in console.due(t):
            if log is not None:
                log.append((t, "console", "sent", data, True))
            relay.inbound(t, "console", data, CONSOLE)
        outbox += [(t + after, data) for destination, data in node.due(t) if destination == FACING["vehicle"]]
        while outbox and outbox[0][0] <= t:
            data = outbox.pop(0)[1]
            if log is not None:
                log.append((t, "vehicle", "sent", data, True))
            relay.inbound(t, "vehicle", data, VEHICLE)
        for to, data in relay.due(t):
            if log is not None:
                log.append((t, to, "received", data, True))
            if to == "console":
                console.receive(t, data)
            else:
                node.receive(t, data, FACING["vehicle"])
        times = [x for x in (console.deadline, node.deadline, relay.deadline, outbox[0][0] if outbox else None)
                 if x is not None]
        t = max(t + 1e-6, min(times)) if times else seconds + 1
    relay.finish(t)
    results = {side: relay.judges[side].result(implementation=f"relay {side}", started="2026-01-01T00:00:00+00:00",
                                               duration=0.0, strict=False, title=SUITE.title, until=seconds)
               for side in SIDES}
    return relay, console, merged(results, strict=False)
