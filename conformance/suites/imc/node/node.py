"""The reference node: what the seeds say a node does, sans-IO (the caller says what time it is and moves the
datagrams). It behaves like DUNE where the seeds are silent: it talks only to systems that announced an
``imc+udp`` service, heart-beats to them at 1 Hz and announces itself to them (unicast only) every 10 s; unlike DUNE
it acts only on requests addressed to it or to anyone (0xFFFF), and, like DUNE, takes no datagram carrying its own id
as a request (its own, heard back, or a forgery). A capability given in ``only_to_itself`` is served to its own system
alone (DUNE serves AcousticRequest so). A
hostile link cannot stall it: a service naming a host rather than an address is ignored (nothing is ever
resolved), a contact not heard from for ``CONTACT_TTL`` seconds is forgotten and at most ``MAX_CONTACTS`` are
kept (a flood of spoofed Announces cannot push out a contact that keeps talking), and a frame the reference
codec does not judge (nested too deep) is dropped and counted like a malformed one.

Acoustic operations go over a simulated channel: each peer has a range, a reply takes the two-way travel
time at 1500 m/s, and the modem is busy until the operation ends. Iridium and SMS go to simulated gateways that
deliver at once unless a message's data asks them to fail, slow down or vanish (the stand-in's rule: gateway.py). ``loss`` and ``dup`` drop and repeat datagrams with a seeded generator; loss touches only
the requests and replies of idempotent exchanges (exchanges.json), which a scenario may resend, and never more than
``LOSS_RUN`` copies of one message.
"""

from __future__ import annotations

import heapq
import ipaddress
import itertools
import random
import re
import struct
from collections import deque

from .. import codec
from ....kinds.vector.errors import NotJudged
from ..crc16 import crc16
from ..definitions import Definitions
from ....kinds.vector.floats import as_float
from ..values import raw_bytes, text_bytes
from ..wire import ImcWire
from . import gateway
from .breaks import BREAKS, VARIANTS

SOUND_SPEED = 1500.0  # m/s
TURNAROUND = 0.05  # s a peer's modem takes to answer
PROCESSING = 0.005  # s the node takes to answer anything
UNKNOWN_SYSTEM, UNKNOWN_ENTITY = 0xFFFF, 0xFF
ACOUSTIC_ENTITY = 43
SERVICE_URL = re.compile(r"imc\+udp://([^:/;]+|\[[0-9a-fA-F:]+\]):([0-9]+)/?")
MAX_CONTACTS = 64
CONTACT_TTL = 30.0  # seconds without a frame from a contact before it is forgotten (DUNE's rule)
LOSS_RUN = 2  # at most this many copies of one message dropped by ``loss``
MAX_LOSS_KEYS = 4096  # messages whose drops are counted at once (then the count starts again)
SLOW_TURNAROUND = 4.0  # s a peer's modem takes to answer under the busy-then-completes variant
# vehicle-traffic: (message id, payload, byte order, every how many 0.2 s ticks) of messages outside the seeds, as a
# DUNE vehicle streams them (IMC.xml 5.4: EstimatedState's 20 fields, EntityState, CpuUsage, EulerAngles, Temperature),
# and an id no IMC.xml defines (999: a newer or private message); with them a HistoricData (``_historic_traffic``)
TRAFFIC_TICK = 0.2
TRAFFIC = ((350, bytes(88), "<", 1), (1, bytes([1, 0]) + struct.pack("<H", 6) + b"Active", "<", 1),
           (7, bytes([12]), "<", 1), (254, bytes(40), "<", 5), (263, struct.pack(">f", 14.5), ">", 5),
           (999, b"\x01\x02\x03", "<", 5))


class ReferenceNode:
    def __init__(self, defs: Definitions, behaviour: dict, *, edition: str, address: tuple[str, int],
                 name: str = "imc-reference", system: int = 0x00A0, peers: dict[str, float] | None = None,
                 loss: float = 0.0, dup: float = 0.0, seed: int = 0, broken: str | None = None,
                 variant: str | None = None, epoch0: float = 1_700_000_000.0, only_to_itself=()):
        if broken is not None and broken not in BREAKS:
            raise ValueError(f"unknown broken behaviour {broken!r}; one of: {', '.join(BREAKS)}")
        if variant is not None and variant not in VARIANTS:
            raise ValueError(f"unknown variant {variant!r}; one of: {', '.join(VARIANTS)}")
        capabilities = behaviour["capabilities"]
        unknown = [c for c in only_to_itself if c not in capabilities]
        if unknown:
            raise ValueError(f"unknown capability {unknown[0]!r}; one of: {', '.join(capabilities)}")
        self.variant = variant
        self.defs, self.wire, self.edition = defs, ImcWire(defs, {}), edition
        self.exchanges = behaviour["exchanges"]
        self.own_only = {m for c in only_to_itself for m in capabilities[c]["requests"]}  # served to itself alone
        self.turnaround = SLOW_TURNAROUND if variant == "busy-then-completes" else TURNAROUND
        self.acoustic_timeout = behaviour["bounds"]["acoustic-queue"]["seconds"]  # each queued operation's, at most
        self.address, self.name, self.system = address, name, system
        self.peers = dict(peers if peers is not None else {"imc-peer-1": 150.0, "imc-peer-2": 1200.0})
        self.loss, self.dup, self.rng, self.broken, self.epoch0 = loss, dup, random.Random(seed), broken, epoch0
        self.loss_runs: dict[tuple, int] = {}  # (message, its fields) -> how many copies of it were dropped
        self.queue: list = []
        self.order = itertools.count()
        self.contacts: dict[int, tuple[str, int]] = {}
        self.heard_at: dict[int, float] = {}  # when each contact last sent a valid frame
        self.strangers: dict[int, tuple[str, int]] = {}  # unannounced senders served (trusts-unannounced), bounded
        self.refused = 0  # Announces ignored: a host name for an address, or the contact table full
        self.modem_free_at = 0.0
        self.beacons: list = []
        self.groups: dict[str, object] = {}  # SystemGroup: group name -> its list of systems
        self.kept: list[dict] = []  # RemoteCommands kept for resending
        self.requests: dict[int, tuple] = {}  # AcousticRequest req_id -> (its tag, when it ends, it, its end state)
        self.cancelled: set[int] = set()  # tags of queued frames not to send (reused-id-cancels)
        self.queries: deque = deque()  # when the latest HistoricDataQueries came (drops-when-many, exhausted-by-many)
        self.dropped_ids: set[int] = set()  # the req_ids of the QUERYs dropped (drops-when-many)
        self.exhausted = False
        self.acoustic_dead = False
        self.lbl_dead = False
        self.dropped = 0  # datagrams that did not decode
        self.unjudged = 0  # frames beyond the reference codec's bounds (nested too deep), dropped as well
        self.next_beat = self.next_announce = None
        self.next_traffic, self.ticks = None, 0  # vehicle-traffic

    # ------------------------------------------------------------------ the caller's interface

    @property
    def deadline(self) -> float | None:
        times = [self.queue[0][0]] if self.queue else []
        times += [x for x in (self.next_beat, self.next_announce, self.next_traffic) if x is not None]
        return min(times, default=None)

    def receive(self, t: float, data: bytes, source: tuple) -> None:
        """A datagram arrived from ``source`` (malformed ones are dropped silently, as DUNE does)."""
        try:
            message = codec.decode(self.defs, data)
        except NotJudged:
            self.unjudged += 1
            return
        except ValueError:
            self.dropped += 1
            if self.broken != "answers-bad-crc" or len(data) < codec.HEADER_SIZE + 2:
                return
            try:  # the broken node recomputes the CRC instead of checking it
                order = codec.ORDERS[codec.byte_order_of(data)]
                message = codec.decode(self.defs, data[:-2] + struct.pack(order + "H", crc16(data[:-2])))
            except (ValueError, KeyError, NotJudged):
                return
        if self.broken == "leaks-on-drop" and self.dropped >= 5000:
            return
        order = codec.byte_order_of(data)
        if self.broken == "ignores-big-endian" and order == "be":
            return
        src, dst = message["header"]["src"], message["header"]["dst"]
        if src in self.contacts:
            self.heard_at[src] = t
        if src == self.system:  # its own id from the link: its own frame heard back, or a forgery
            self.acoustic_dead = self.acoustic_dead or self.broken == "dies-on-own-id"
            if self.broken != "trusts-own-id":
                return
        if message["abbrev"] == "Announce":
            self._contact(t, src, _text(message["fields"]["services"]), source)
            return
        if src not in self.contacts and src != self.system:
            if self.variant != "trusts-unannounced":
                return
            self.strangers.pop(src, None)
            self.strangers[src] = source
            while len(self.strangers) > MAX_CONTACTS:
                del self.strangers[next(iter(self.strangers))]
        if self._lost(message) or self.exhausted or not self._for_me(message, dst):
            return
        if message["abbrev"] in self.own_only and src != self.system:
            return  # a local service: only the node's own system may ask for it
        handler = getattr(self, "_on_" + message["abbrev"], None)
        if handler is not None:
            handler(t, message)

    def _for_me(self, message: dict, dst: int) -> bool:
        """Whether the node acts on a request addressed to ``dst``: to it or to anyone; a query addressed elsewhere
        too under answers-queries-for-others (a query changes nothing)."""
        if dst == UNKNOWN_SYSTEM:
            return self.broken != "ignores-anyone"
        if dst == self.system or self.broken == "acts-on-others-requests":
            return True
        return self.variant == "answers-queries-for-others" and self._idempotent(message, reply=False)

    def due(self, t: float) -> list[tuple[tuple, bytes]]:
        """The datagrams to send by time ``t``: (destination address, bytes)."""
        out = []
        for src in [s for s, heard in self.heard_at.items() if t - heard > CONTACT_TTL]:
            del self.contacts[src], self.heard_at[src]
        if self.next_beat is not None and self.next_beat <= t:
            self.next_beat = t + 1.0
            if self.broken != "no-heartbeat":
                out += [(addr, self._frame(t, "Heartbeat", {}, dst=UNKNOWN_SYSTEM, ent=0)) for addr in self.contacts.values()]
        if self.next_announce is not None and self.next_announce <= t:
            self.next_announce = t + (60.0 if self.variant == "slow-announce" else 10.0)
            out += [(addr, self._announce(t)) for addr in self.contacts.values()]
        if self.next_traffic is not None and self.next_traffic <= t:
            self.next_traffic, self.ticks = t + TRAFFIC_TICK, self.ticks + 1
            out += [(addr, frame) for frame in self._traffic(t) for addr in self.contacts.values()]
        while self.queue and self.queue[0][0] <= t:
            _, _, dest, data, tag = heapq.heappop(self.queue)
            if tag not in self.cancelled:
                out.append((dest, data))
        return out

    # ------------------------------------------------------------------ discovery

    def _contact(self, t: float, src: int, services: str, source: tuple) -> None:
        for host, port in SERVICE_URL.findall(services):
            try:
                address = (str(ipaddress.ip_address(host.strip("[]"))), int(port))
            except ValueError:  # a name: resolving it would stall the node (and could go anywhere)
                self.refused += 1
                continue
            if not 0 < address[1] < 0x10000:
                self.refused += 1
                continue
            fresh = src not in self.contacts
            if fresh and len(self.contacts) >= MAX_CONTACTS:
                self.refused += 1
                return
            self.contacts[src], self.heard_at[src] = address, t
            if fresh:
                period = 60.0 if self.variant == "slow-announce" else 10.0
                if self.variant != "slow-announce":
                    self._later(t, PROCESSING, address, self._announce(t))
                self.next_beat = t if self.next_beat is None else self.next_beat
                if self.variant == "vehicle-traffic" and self.next_traffic is None:
                    self.next_traffic = t
                self.next_announce = t + period if self.next_announce is None else self.next_announce
            return

    def _announce(self, t: float) -> bytes:
        host, port = self.address
        host = f"[{host}]" if ":" in host else host
        services = f"imc+udp://{host}:{port}/;imc+info://0.0.0.0/version/{self.edition.removeprefix('imc-')}"
        fields = {"sys_name": self.name, "sys_type": 99 if self.broken == "unknown-system-type" else 2,
                  "owner": UNKNOWN_SYSTEM, "lat": 0.0, "lon": 0.0,
                  "height": 0.0, "services": services}
        return self._frame(t, "Announce", fields, dst=0, ent=0, dst_ent=0)

    # ------------------------------------------------------------------ requests

    def _on_AcousticSystemsQuery(self, t: float, message: dict) -> None:
        names = ",".join(self.peers) + ("," if self.broken == "list-empty-items" else "")
        self._reply(t, PROCESSING, message, "AcousticSystems", {"list": names})
        if self.broken == "two-replies":
            self._reply(t, PROCESSING + 0.1, message, "AcousticSystems", {"list": names})

    def _on_AcousticSystems(self, t: float, message: dict) -> None:
        if self.broken == "answers-unsolicited-systems":  # a reply taken for a query
            self._on_AcousticSystemsQuery(t, message)

    def _on_SystemGroup(self, t: float, message: dict) -> None:
        """Set and Chg store a group's list of systems, Dis forgets it, Req is answered with a Rep."""
        f = message["fields"]
        action, name = self._name("SystemGroup", "Action", f["Action"]), _text(f["GroupName"])
        if action in ("Set", "Chg"):
            self.groups.pop(name, None)
            self.groups[name] = f["GroupList"]
            while len(self.groups) > MAX_CONTACTS:
                del self.groups[next(iter(self.groups))]
        elif action == "Dis":
            self.groups.pop(name, None)
        elif action == "Req" and self.broken != "no-group-report":
            self._reply(t, PROCESSING, message, "SystemGroup", {"GroupName": f["GroupName"],
                                                                "Action": self._v("SystemGroup", "Action", "Rep"),
                                                                "GroupList": self.groups.get(name, "")})

    def _on_LblConfig(self, t: float, message: dict) -> None:
        op = message["fields"]["op"]
        if self.lbl_dead:
            return
        if op == self._v("LblConfig", "op", "SET_CFG"):
            merged = self.beacons if self.broken == "merges-set-cfg" else []
            self.beacons = merged + [_rounded(b) if self.broken == "rounds-beacons" else b for b in message["fields"]["beacons"]]
            if self.broken == "acknowledges-set-cfg":
                self._reply(t, PROCESSING, message, "LblConfig", {"op": self._v("LblConfig", "op", "CUR_CFG"),
                                                                  "beacons": self.beacons})
        elif op == self._v("LblConfig", "op", "GET_CFG") and self.broken != "no-cur-cfg":
            beacons = self.beacons[:-1] if self.broken == "other-beacons" else self.beacons
            self._reply(t, PROCESSING, message, "LblConfig", {"op": self._v("LblConfig", "op", "CUR_CFG"), "beacons": beacons})
        elif op == self._v("LblConfig", "op", "CUR_CFG"):
            if self.broken == "stores-cur-cfg":  # a reply to someone's GET_CFG: it changes nothing
                self.beacons = list(message["fields"]["beacons"])
        elif self.broken == "stops-after-unknown-op":  # an operation it does not know: ignored
            self.lbl_dead = True

    def _on_AcousticOperation(self, t: float, message: dict) -> None:
        if self.acoustic_dead:
            return
        f = message["fields"]
        op = self._name("AcousticOperation", "op", f["op"])
        plans = {"RANGE": ("RANGE_IP", "RANGE_RECVED", "RANGE_TIMEOUT"), "REVERSE_RANGE": ("RANGE_IP", "RANGE_RECVED", "RANGE_TIMEOUT"),
                 "MSG": ("MSG_IP", "MSG_DONE", "MSG_FAILURE"), "MSG_SHORT": ("MSG_IP", "MSG_DONE", "MSG_FAILURE"),
                 "ABORT": ("ABORT_IP", "ABORT_ACKED", "ABORT_TIMEOUT")}
        system = "imc-other-system" if self.broken == "wrong-system" else f["system"]

        def state(delay: float, name: str, range_: float = 0.0) -> None:
            fields = {"op": self._v("AcousticOperation", "op", name), "system": system, "range": range_, "msg": None}
            self._reply(t, delay, message, "AcousticOperation", fields, entity=ACOUSTIC_ENTITY)

        if op is None and self.broken != "silent-on-unsupported":  # an operation the definitions do not have
            state(PROCESSING, "MSG_FAILURE" if self.broken == "unsupported-as-failure" else "UNSUPPORTED")
        if op not in plans:
            return  # a state (sent by another node), not a request
        distance = self.peers.get(_text(f["system"]))
        if distance is None and self.variant == "silent-to-unknown-systems":
            return  # it cannot route the request
        if t < self.modem_free_at:
            if self.variant == "queues-operations":  # carried out once the operations before it are done
                self._on_AcousticOperation(self.modem_free_at, message)
                return
            state(PROCESSING, "BUSY")
            if self.variant == "busy-then-completes":
                self._on_AcousticOperation(self.modem_free_at, message)
            return
        progress, success, failure = plans[op]
        silent = self.variant == "silent-where-allowed"
        if silent and (op in ("MSG_SHORT", "REVERSE_RANGE") or f["msg"] is None and op == "MSG"):
            return
        if op == "REVERSE_RANGE" and self.variant == "declines-reverse-range":
            state(PROCESSING, "UNSUPPORTED")
            return
        if op in ("MSG", "MSG_SHORT") and f["msg"] is None:
            state(PROCESSING, failure)  # nothing to send: the request cannot be fulfilled
            return
        if self.broken == "wrong-kind-terminal" and op == "RANGE":
            success = "MSG_DONE"
        if self.broken == "msg-ends-in-range" and op == "MSG":
            success = "RANGE_RECVED"
        if self.broken == "silent-on-abort" and op == "ABORT" and distance is not None:
            return
        travel = 2.0 if distance is None else 2 * distance / SOUND_SPEED + self.turnaround
        if distance is None and self.variant == "queues-operations":  # no answer: it gives up at its acoustic timeout
            travel = float(self.acoustic_timeout)
        self.modem_free_at = t + travel
        if self.variant == "queued-first" and progress == "MSG_IP":
            state(PROCESSING / 2, "MSG_QUEUED")
        state(PROCESSING, progress)
        if distance is None:
            reached = (op == "ABORT" and self.broken == "acks-unreachable"
                       or op == "MSG" and self.variant == "msg-to-unreachable-done")
            state(travel, success if reached else failure)
        else:
            state(travel, success, float(distance) if "RANGE" in op else 0.0)

    def _on_AcousticRequest(self, t: float, message: dict) -> None:
        if self.acoustic_dead:
            return
        f = message["fields"]
        kind = self._name("AcousticStatus", "type", f["type"])
        if self.broken == "dies-after-raw" and kind == "RAW":
            self.acoustic_dead = True
            return
        echoed_type = self._v("AcousticStatus", "type", "MSG") if self.broken == "type-not-echoed" else f["type"]
        req_id = (f["req_id"] + 1) % 0x10000 if self.broken == "req-id-not-echoed" else f["req_id"]
        tag, previous = next(self.order), self.requests.get(f["req_id"])
        if previous is not None and previous[1] > t and self._reused(t, message, previous):
            return

        def status(delay: float, name: str, range_: float = 0.0, info: str = "") -> None:
            fields = {"req_id": req_id, "type": echoed_type, "status": self._status(name), "info": info, "range": range_}
            self._reply(t, delay, message, "AcousticStatus", fields, entity=ACOUSTIC_ENTITY, tag=tag)

        distance = self.peers.get(_text(f["destination"]))
        if distance is None and self.variant == "silent-to-unknown-systems":
            return  # it cannot route the request
        if kind == "REVERSE_RANGE" and self.variant in ("silent-where-allowed", "declines-reverse-range"):
            if self.variant == "declines-reverse-range":
                status(PROCESSING, "UNSUPPORTED", info="reverse ranges are not supported")
            return
        if t < self.modem_free_at:
            status(PROCESSING, "BUSY", info="the modem is busy")
            if self.variant == "busy-then-completes":
                self._on_AcousticRequest(self.modem_free_at, message)
            return
        if kind == "RAW" and (f["msg"] is None or f["msg"]["abbrev"] != "DevDataBinary") and self.broken != "raw-accepted":
            status(PROCESSING, "UNSUPPORTED", info="RAW expects a DevDataBinary")
            return
        if kind == "MSG" and f["msg"] is None:
            status(PROCESSING, "INPUT_FAILURE", info="no message to send")
            return
        if distance is None:
            status(PROCESSING, *(("SENT",) if self.broken == "succeeds-to-unknown" else ("INV_ADDR", 0.0, "unknown destination")))
            return
        travel = 2 * distance / SOUND_SPEED + self.turnaround
        timeout = as_float(f["timeout"])
        if self.broken == "ignores-timeout":
            travel += timeout + 2.0
        self.modem_free_at = t + travel
        final = "RANGE_RECEIVED" if "RANGE" in kind else "SENT"
        self.requests[f["req_id"]] = (tag, t + travel, message, final, float(distance) if "RANGE" in kind else 0.0)
        if self.variant == "queued-first":
            status(PROCESSING / 2, "QUEUED")
        status(PROCESSING, "IN_PROGRESS")
        if self.broken == "no-terminal":
            return
        if travel > timeout and self.broken != "ignores-timeout":  # the request's time is up before the peer's answer
            self.modem_free_at = t + timeout
            status(timeout, "INPUT_FAILURE", info="timed out")
            return
        if final == "RANGE_RECEIVED" and self.variant == "sent-before-range-received":
            status(travel / 2, "SENT")
        status(travel, final, float(distance) if final == "RANGE_RECEIVED" else 0.0)
        if self.broken == "status-after-terminal":
            status(travel + 0.1, "IN_PROGRESS")
        elif self.broken == "two-terminals":
            status(travel + 0.1, "ERROR", info="second final status")

    def _reused(self, t: float, message: dict, previous: tuple) -> bool:
        """A request reusing the req_id of an outstanding one: whether it is dealt with here (not carried out as a
        request of its own). The seeds leave it open: it may replace the first (reused-id-replaces) or cancel it
        (reused-id-cancels); broken, it crosses the two (the first's end reported with the second's type) or stops
        the node's acoustic service."""
        first_tag, end, first, final, range_ = previous
        if self.variant in ("reused-id-replaces", "reused-id-cancels") or self.broken in ("reused-id-crossed",
                                                                                         "dies-on-reused-id"):
            self.cancelled.add(first_tag)  # the first says nothing more of itself
            self.modem_free_at = t
        if self.broken == "dies-on-reused-id":
            self.acoustic_dead = True
            return True
        if self.variant == "reused-id-cancels":  # the first ends now, in a failure; the second is not carried out
            fields = {"req_id": first["fields"]["req_id"], "type": first["fields"]["type"], "status": self._status("ERROR"),
                      "info": "cancelled: a request reused its id", "range": 0.0}
            self._reply(t, PROCESSING, first, "AcousticStatus", fields, entity=ACOUSTIC_ENTITY)
            return True
        if self.broken == "reused-id-crossed":  # the first's end, reported under the second's type
            self.modem_free_at = end
            fields = {"req_id": first["fields"]["req_id"], "type": message["fields"]["type"],
                      "status": self._status(final), "info": "", "range": range_}
            self._reply(t, end - t, first, "AcousticStatus", fields, entity=ACOUSTIC_ENTITY)
            return False
        return False

    def _on_IridiumMsgTx(self, t: float, message: dict) -> None:
        req_id, ttl = message["fields"]["req_id"], message["fields"]["ttl"]
        req_id = (req_id + 1) % 0x10000 if self.broken == "req-id-not-echoed" else req_id
        late = ttl + 4.0 if self.broken in ("transmits-after-ttl", "late-ok") else 0.0
        states = ((PROCESSING, "QUEUED", ""), (0.2 + late, "TRANSMIT", ""), (0.5 + late, "OK", ""))
        if self.variant == "slow-iridium-link":  # sent before a ttl of 2 s, its OK 1.8 s after it
            states = ((PROCESSING, "QUEUED", ""), (1.9, "TRANSMIT", ""), (3.8, "OK", ""))
        states = states[::2] if self.broken == "late-ok" else states
        states = gateway.simulated(self._gateway_mode(message), ttl, states, "TRANSMIT", "EXPIRED", "ERROR", self.broken)
        for delay, name, text in states:
            fields = {"req_id": req_id, "status": self._v("IridiumTxStatus", "status", name), "text": text}
            self._reply(t, delay, message, "IridiumTxStatus", fields)

    def _on_SmsTx(self, t: float, message: dict) -> None:
        seq = message["fields"]["seq"]
        seq = (seq + 1) % 0x100000000 if self.broken == "seq-not-echoed" else seq
        states = ((PROCESSING, "ACCEPTED", ""), (0.2, "TRANSMITTING", ""), (0.5, "COMPLETED", ""))
        mode = self._gateway_mode(message)
        states = gateway.simulated(mode, message["fields"]["timeout"], states, "TRANSMITTING", "INTERRUPTED",
                                   "REJECTED" if mode == "gone" else "INTERRUPTED", self.broken)
        for delay, name, error in states:
            self._reply(t, delay, message, "SmsState", {"seq": seq, "state": self._v("SmsState", "state", name), "error": error})

    def _gateway_mode(self, message: dict) -> str:
        """What the simulated gateway does with a message: the stand-in's rule (gateway.py), read from its data."""
        try:
            mode = gateway.plan(raw_bytes(message["fields"]["data"]))
        except ValueError:
            return "ok"
        return "ok" if self.broken == "ok-when-gateway-fails" and mode in ("fail", "gone") else mode

    def _on_HistoricDataQuery(self, t: float, message: dict) -> None:
        f = message["fields"]
        req_id = (f["req_id"] + 1) % 0x10000 if self.broken == "req-id-not-echoed" else f["req_id"]
        kind = self._name("HistoricDataQuery", "type", f["type"])
        self.queries.append(t)
        while self.queries and self.queries[0] < t - 1.0:
            self.queries.popleft()
        if self.broken == "exhausted-by-many" and len(self.queries) >= 80:
            self.exhausted = True  # no request is served from now on
        if self.broken == "drops-when-many" and kind == "QUERY" and (len(self.queries) > 4 or req_id in self.dropped_ids):
            self.dropped_ids.add(req_id)
            return
        if kind == "CLEAR":
            if self.broken != "clear-keeps-data":
                self.kept.clear()
            fields = {"req_id": req_id, "type": f["type"], "max_size": f["max_size"], "data": None}
        elif kind == "QUERY" or kind == "REPLY" and self.broken == "answers-replies":
            fields = {"req_id": req_id, "type": self._v("HistoricDataQuery", "type", "REPLY"), "max_size": f["max_size"],
                      "data": self._historic_data(t, f["max_size"])}
        else:
            return
        self._reply(t, PROCESSING, message, "HistoricDataQuery", fields)

    def _historic_data(self, t: float, max_size: int) -> dict | None:
        """The kept items, highest priority first, as a HistoricData of at most ``max_size`` bytes (as many
        items as fit; none when not even an empty one fits); RemoteCommands whose timeout passed are dropped."""
        if self.broken not in ("resends-expired", "keeps-expired-commands"):
            self.kept = [m for m in self.kept if m["abbrev"] != "RemoteCommand"
                         or as_float(m["fields"]["timeout"]) > self.epoch0 + t]
        items = list(self.kept)
        if self.broken != "transmits-in-arrival-order":
            items.sort(key=lambda m: -m["fields"].get("priority", 0))
        while True:
            data = {"abbrev": "HistoricData", "fields": {"base_lat": 0.0, "base_lon": 0.0, "base_time": 0.0, "data": items}}
            if self.broken == "ignores-max-size" or self.wire.size_of("HistoricDataQuery", "data", data) <= max_size:
                return data if items or self.broken == "ignores-max-size" else None
            if not items or self.broken == "empty-when-small":
                return None
            items = items[:-1]

    def _on_HistoricData(self, t: float, message: dict) -> None:
        """Data for the disruption tolerant network: samples are kept for transmission (those of priority -127
        are only logged), RemoteCommands inside are handled as if received alone."""
        for item in message["fields"]["data"]:
            if item is None:
                continue
            if item["abbrev"] == "HistoricSample" and (item["fields"]["priority"] > -127
                                                       or self.broken == "transmits-logged-samples"):
                if self.broken == "rewrites-producer":
                    item = {**item, "fields": {**item["fields"], "sys_id": message["header"]["src"]}}
                self.kept.append(item)
            elif item["abbrev"] == "RemoteCommand":
                self._on_RemoteCommand(t, dict(message, abbrev="RemoteCommand", fields=item["fields"]))

    def _on_CompressedHistory(self, t: float, message: dict) -> None:
        """Not read (a reading the seeds leave open: compressed-history-input); the broken node stops serving."""
        self.exhausted = self.exhausted or self.broken == "dies-on-compressed-history"

    def _on_RemoteCommand(self, t: float, message: dict) -> None:
        f = message["fields"]
        if f["destination"] == self.system or self.broken == "executes-others-commands":
            if f["cmd"] is not None and self.broken != "ignores-remote-commands":
                self._execute(t, f)
            if f["destination"] == self.system:
                return
        if as_float(f["timeout"]) > self.epoch0 + t or self.broken == "keeps-expired-commands":
            self.kept.append({"abbrev": "RemoteCommand", "fields": f})
            self._forward(t)
        elif self.broken == "forwards-expired" and f["destination"] in self.contacts:
            self.kept.append({"abbrev": "RemoteCommand", "fields": f})
            self._forward(t)

    def _forward(self, t: float) -> None:
        """Resend the kept RemoteCommands whose recipient is a contact (as DUNE does over Wi-Fi, inside
        HistoricData); the others stay kept for a QUERY's reply."""
        if self.broken == "never-forwards":
            return
        for command in [c for c in self.kept if c["abbrev"] == "RemoteCommand" and c["fields"]["destination"] in self.contacts]:
            self.kept.remove(command)
            destination = command["fields"]["destination"]
            if self.broken == "forwards-as-own":
                command = {**command, "fields": {**command["fields"], "original_source": self.system}}
            data = {"base_lat": 0.0, "base_lon": 0.0, "base_time": 0.0, "data": [command]}
            frame = self._frame(t + PROCESSING, "HistoricData", data, dst=destination, ent=0)
            self._later(t, PROCESSING, self.contacts[destination], frame)

    def _execute(self, t: float, command: dict) -> None:
        """Unpack a command for this node: handle it as a request from its original source."""
        handler = getattr(self, "_on_" + command["cmd"]["abbrev"], None)
        if handler is None or command["cmd"]["abbrev"] == "RemoteCommand":
            return
        header = {"timestamp": self.epoch0 + t, "src": command["original_source"], "src_ent": UNKNOWN_ENTITY,
                  "dst": self.system, "dst_ent": UNKNOWN_ENTITY}
        handler(t, {"abbrev": command["cmd"]["abbrev"], "header": header, "fields": command["cmd"]["fields"], "executed": True})

    # ------------------------------------------------------------------ sending

    def _reply(self, t: float, delay: float, request: dict, abbrev: str, fields: dict, entity: int = 0,
               tag: int | None = None) -> None:
        header = request["header"]
        src = next(iter(self.contacts), header["src"]) if self.broken == "replies-to-first-client" else header["src"]
        address = self.contacts.get(src) or self.strangers.get(src)
        if address is None:
            return
        dst, dst_ent = (UNKNOWN_SYSTEM, UNKNOWN_ENTITY) if self.broken == "broadcast-replies" else (src, header["src_ent"])
        if self.broken == "late":
            delay += 30.0
        frame = self._frame(t + delay, abbrev, fields, dst=dst, ent=entity, dst_ent=dst_ent)
        resendable = not request.get("executed")  # a command carried in HistoricData is never sent again
        if resendable and self._lost({"abbrev": abbrev, "fields": fields}, reply=True):
            return
        self._later(t, delay, address, frame, tag)
        if self.dup and self.rng.random() < self.dup:
            self._later(t, delay + 0.001, address, frame, tag)
        if self.broken == "replies-to-every-client":
            for other, where in self.contacts.items():
                if other != dst:
                    copy = self._frame(t + delay + 0.001, abbrev, fields, dst=other, ent=entity, dst_ent=dst_ent)
                    self._later(t, delay + 0.001, where, copy, tag)

    def _later(self, t: float, delay: float, address: tuple, frame: bytes, tag: int | None = None) -> None:
        heapq.heappush(self.queue, (t + delay, next(self.order), address, frame, tag))

    def _frame(self, t: float, abbrev: str, fields: dict, *, dst: int, ent: int, dst_ent: int = UNKNOWN_ENTITY) -> bytes:
        src = 0x0BAD if self.broken == "from-other-system" and abbrev not in ("Heartbeat", "Announce") else self.system
        header = {"timestamp": self.epoch0 + t, "src": src, "src_ent": ent, "dst": dst, "dst_ent": dst_ent}
        message = {"abbrev": abbrev, "header": header, "fields": fields}
        if self.broken == "big-endian-le-crc" and abbrev not in ("Heartbeat", "Announce"):
            frame = codec.encode(self.defs, message, "be")
            return frame[:-2] + struct.pack("<H", crc16(frame[:-2]))
        frame = codec.encode(self.defs, message, "le")
        if self.broken == "malformed-reply" and abbrev == "AcousticSystems":
            size = struct.unpack_from("<H", frame, 4)[0] + 4
            body = frame[:4] + struct.pack("<H", size) + frame[6:-2]
            return body + struct.pack("<H", crc16(body))
        return frame

    # ------------------------------------------------------------------ helpers

    def _traffic(self, t: float) -> list[bytes]:
        """The frames of its other traffic due at this tick (vehicle-traffic), to anyone: messages the seeds do not
        define, so built from their ids and payloads."""
        out = []
        for mgid, payload, e, every in (*TRAFFIC, self._historic_traffic()):
            if self.ticks % every == 0:
                body = struct.pack(e + "HHHdHBHB", self.defs.sync, mgid, len(payload), self.epoch0 + t, self.system, 0,
                                   UNKNOWN_SYSTEM, UNKNOWN_ENTITY) + payload
                out.append(body + struct.pack(e + "H", crc16(body)))
        return out

    def _historic_traffic(self) -> tuple[int, bytes, str, int]:
        """A HistoricData of its data store, as ``TRAFFIC`` holds them: one HistoricSample holding an EstimatedState
        (a message the seeds do not define, inline: read with the whole IMC.xml), once a second."""
        sample = struct.pack("<HHbhhhhH", self.defs["HistoricSample"].id, self.system, 0, 1, 2, 3, 4, 350) + bytes(88)
        return self.defs["HistoricData"].id, struct.pack("<fffH", 0.7, -0.15, 100.0, 1) + sample, "<", 5

    def _lost(self, message: dict, reply: bool = False) -> bool:
        """Drop at random (``loss``) a request or reply of an idempotent exchange; never more than ``LOSS_RUN``
        copies of one message (a scenario resends a few times: a link that loses every try is a dead link, not a
        lossy one; counted per message, not per kind, as other traffic between two tries must not reset it)."""
        if not self.loss or not self._idempotent(message, reply):
            return False
        key = (message["abbrev"], repr(message["fields"]))  # a resent request, or its reply, is the same message
        dropped = self.loss_runs.get(key, 0)
        lost = dropped < LOSS_RUN and self.rng.random() < self.loss
        if lost:
            if len(self.loss_runs) >= MAX_LOSS_KEYS:
                self.loss_runs.clear()
            self.loss_runs[key] = dropped + 1
        return lost

    def _idempotent(self, message: dict, reply: bool) -> bool:
        for ex in self.exchanges:
            name, when = (ex["reply"], ex.get("reply_when", {})) if reply else (ex["request"]["message"], ex["request"].get("when", {}))
            if name == message["abbrev"] and all(message["fields"].get(f) in [self._v(name, f, v) for v in values]
                                                 for f, values in when.items()):
                return ex["idempotent"]
        return False

    def _v(self, message: str, path: str, name: str):
        try:
            return self.wire.resolve(message, path, name, self.edition)
        except KeyError:
            return None

    def _status(self, name: str) -> int:
        """AcousticStatus.status by name; the seeds' edition lacks UNSUPPORTED (666 fits no uint8, E1) and
        INV_ADDR: INPUT_FAILURE and ERROR stand in."""
        if name == "UNSUPPORTED" and self.variant == "old-unsupported-code":
            return 154  # 666 truncated to a byte (erratum E1)
        value = self._v("AcousticStatus", "status", name)
        if value is None or value > 0xFF:
            value = self._v("AcousticStatus", "status", {"UNSUPPORTED": "INPUT_FAILURE", "INV_ADDR": "ERROR"}[name])
        return value

    def _name(self, message: str, path: str, value: int) -> str | None:
        for v in self.defs[message].field(path).enum_values:
            if v.value == value and v.in_edition(self.edition):
                return v.abbrev
        return None


def _rounded(beacon: dict | None) -> dict | None:
    """A beacon with its latitude and longitude kept as fp32 (rounds-beacons)."""
    if beacon is None:
        return None
    fields = dict(beacon["fields"])
    for name in ("lat", "lon"):
        fields[name] = struct.unpack("<f", struct.pack("<f", as_float(fields[name])))[0]
    return {**beacon, "fields": fields}


def _text(value) -> str:
    """A plaintext field as text (bytes that are not UTF-8 replaced), whatever its decoded form."""
    return text_bytes(value).decode("utf-8", "replace")
