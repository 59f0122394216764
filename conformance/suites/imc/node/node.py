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
from ..wire import ImcWire
from .acoustic import SLOW_TURNAROUND, TURNAROUND, Acoustic
from .breaks import BREAKS, VARIANTS
from .framing import PROCESSING, UNKNOWN_SYSTEM, Framing, text_of
from .gateway_requests import GatewayRequests
from .history import History
from .link import TRAFFIC_TICK, Link

SERVICE_URL = re.compile(r"imc\+udp://([^:/;]+|\[[0-9a-fA-F:]+\]):([0-9]+)/?")
MAX_CONTACTS = 64
CONTACT_TTL = 30.0  # seconds without a frame from a contact before it is forgotten (DUNE's rule)
FORWARD_PERIOD = 30.0  # seconds between two forwardings of the kept commands (forwards-on-period: DUNE's Wi-Fi period)
LBL_PERIOD = 2.0  # seconds between two LblRanges while it navigates with LBL (beacons set, an acoustic peer)
COPY_WINDOW = 1.0  # seconds within which answers-a-copy-once takes a byte-identical datagram for the link's copy
LBL_RANGE, LBL_STEP = 500.0, 100.0  # metres: the simulated range of the first beacon, and how much further each next one is


class ReferenceNode(Acoustic, GatewayRequests, History, Link, Framing):
    """The reference node: datagrams in with ``receive``, out with ``due``; ``deadline`` says when next to call."""

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
        self.ranging: dict[str, tuple] = {}  # AcousticOperation RANGE under way: system -> (its tag, when it ends)
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
        self.next_forward = None  # forwards-on-period: when the kept commands are next forwarded
        self.next_lbl, self.lbl_turn = None, 0  # LBL navigation: when the next LblRange is due, and for which beacon
        self.last_datagram: tuple = (b"", float("-inf"))  # answers-a-copy-once: the latest datagram, and when it came

    # ------------------------------------------------------------------ the caller's interface

    @property
    def deadline(self) -> float | None:
        times = [self.queue[0][0]] if self.queue else []
        times += [x for x in (self.next_beat, self.next_announce, self.next_traffic, self.next_lbl, self.next_forward)
                  if x is not None]
        return min(times, default=None)

    def receive(self, t: float, data: bytes, source: tuple) -> None:
        """A datagram arrived from ``source`` (malformed ones are dropped silently, as DUNE does)."""
        if self.variant == "answers-a-copy-once":  # a byte-identical copy of the datagram just taken: the link's
            if data == self.last_datagram[0] and t - self.last_datagram[1] < COPY_WINDOW:
                return
            self.last_datagram = (data, t)
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
            self._contact(t, src, text_of(message["fields"]["services"]), source)
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
            if self.broken not in ("no-heartbeat", "beats-only-when-answered"):
                out += [(addr, self._frame(t, "Heartbeat", {}, dst=UNKNOWN_SYSTEM, ent=0)) for addr in self.contacts.values()]
        if self.next_announce is not None and self.next_announce <= t:
            self.next_announce = t + (60.0 if self.variant == "slow-announce" else 10.0)
            out += [(addr, self._announce(t)) for addr in self.contacts.values()]
        if self.next_traffic is not None and self.next_traffic <= t:
            self.next_traffic, self.ticks = t + TRAFFIC_TICK, self.ticks + 1
            out += [(addr, frame) for frame in self._traffic(t) for addr in self.contacts.values()]
        if self.next_forward is not None and self.next_forward <= t:
            self.next_forward = t + FORWARD_PERIOD
            self._forward(t, periodic=True)
        if self.next_lbl is not None and self.next_lbl <= t:
            out += [(addr, frame) for frame in self._lbl_range(t) for addr in self.contacts.values()]
        while self.queue and self.queue[0][0] <= t:
            _, _, dest, data, tag = heapq.heappop(self.queue)
            if tag not in self.cancelled:
                out.append((dest, data))
        return out

    def _lbl_range(self, t: float) -> list[bytes]:
        """While it navigates with LBL (beacons set, an acoustic peer to range with), one LblRange every
        ``LBL_PERIOD`` seconds, to each beacon in turn: its place in the configuration and a simulated range."""
        self.next_lbl = t + LBL_PERIOD if self.beacons and self.peers else None
        if self.next_lbl is None or self.broken == "no-lbl-ranges":
            return []
        beacon = self.lbl_turn % len(self.beacons)
        self.lbl_turn += 1
        fields = {"id": beacon, "range": LBL_RANGE + LBL_STEP * beacon}
        return [self._frame(t, "LblRange", fields, dst=UNKNOWN_SYSTEM, ent=0)]

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
                self._forward(t)  # the kept commands for a system that has just appeared
                if self.variant == "forwards-on-period" and self.next_forward is None:
                    self.next_forward = t + FORWARD_PERIOD
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

    def _on_Heartbeat(self, t: float, message: dict) -> None:
        """A peer's Heartbeat: the reference node answers none (as DUNE); some nodes send one back to that peer."""
        if self.variant == "answers-heartbeats" or self.broken == "beats-only-when-answered":
            self._reply(t, PROCESSING, message, "Heartbeat", {})

    def _on_SystemGroup(self, t: float, message: dict) -> None:
        """Set and Chg store a group's list of systems, Dis forgets it, Req is answered with a Rep."""
        f = message["fields"]
        action, name = self._name("SystemGroup", "Action", f["Action"]), text_of(f["GroupName"])
        if action in ("Set", "Chg"):
            self.groups.pop(name, None)
            self.groups[name] = f["GroupList"]
            while len(self.groups) > MAX_CONTACTS:
                del self.groups[next(iter(self.groups))]
        elif action == "Dis" and self.broken != "keeps-disbanded-group":
            self.groups.pop(name, None)
        elif action == "Req" and self.broken != "no-group-report" and (
                name in self.groups or self.variant != "silent-on-unknown-group"):
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
            self.next_lbl = t + LBL_PERIOD if self.beacons and self.peers else None
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


def _rounded(beacon: dict | None) -> dict | None:
    """A beacon with its latitude and longitude kept as fp32 (rounds-beacons)."""
    if beacon is None:
        return None
    fields = dict(beacon["fields"])
    for name in ("lat", "lon"):
        fields[name] = struct.unpack("<f", struct.pack("<f", as_float(fields[name])))[0]
    return {**beacon, "fields": fields}
