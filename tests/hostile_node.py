"""A hostile IMC node for the second hardening round: the reference node, sans-IO, with one misbehaviour of the link
or of its neighbours per mode. Each mode is something a correct node's verdicts must survive: the suite may say
INCONCLUSIVE (it could not see) but never FAIL the node for it. Run on virtual time (tests/live_harness.py).

Modes:
- ``deep-nesting``: with every heartbeat, an AcousticMessage whose inline messages nest 300 deep (valid IMC,
  beyond the reference codec's bound);
- ``flood``: once the node has replies due, 5,000 Heartbeats go out just before them, more than the session's
  receive queue holds (the link's ``capacity``): replies are lost the way a kernel drops them;
- ``impostor-announce``: an Announce with the session's own id for another service (a second run with the same
  ``--src``), after which the node sends the session's replies to that other run for a while;
- ``impostor-replies``: replies addressed to the session's id that answer requests it never sent (another run's),
  while its own go elsewhere for a while;
- ``echo-only``: the node is silent and the session hears only its own frames back (its Announce on a
  discovery port of its own host).
"""

from __future__ import annotations

import struct

from imc_conformance.suites.imc import codec
from imc_conformance.suites.imc.crc16 import crc16
from imc_conformance.suites.imc.node import ReferenceNode

MODES = ("deep-nesting", "flood", "impostor-announce", "impostor-replies", "echo-only")
REDIRECTED = 15.0  # seconds the node sends the session's replies to the impostor


def nested_frame(depth: int, src: int = 0x00A0, dst: int = 0xFFFF, order: str = "<") -> bytes:
    """An AcousticMessage holding AcousticMessages ``depth`` deep around a LblRange: valid IMC."""
    inner = struct.pack(order + "HBf", 200, 1, 10.5)  # LblRange id, then its payload
    payload = struct.pack(order + "H", 206) * (depth - 1) + inner
    head = struct.pack(order + "HHHdHBHB", 0xFE54, 206, len(payload), 1.7e9, src, 0, dst, 0xFF)
    body = head + payload
    return body + struct.pack(order + "H", crc16(body))


class HostileNode:
    def __init__(self, node: ReferenceNode, mode: str):
        if mode not in MODES:
            raise ValueError(mode)
        self.node, self.mode = node, mode
        self.session: int | None = None  # the session's id, from what it sends
        self.address: tuple | None = None
        self.flooded = self.impersonated = False
        self.redirect_until = -1.0
        self.next_deep = 0.0

    @property
    def deadline(self):
        if self.mode == "echo-only":
            return None
        times = [t for t in (self.node.deadline, self.next_deep if self.mode == "deep-nesting" else None) if t is not None]
        return min(times, default=None)

    def receive(self, t: float, data: bytes, source: tuple) -> None:
        if self.mode == "echo-only":
            self.echo = getattr(self, "echo", []) + [(source, data)]
            return
        if self.session is None and len(data) >= 20 and codec.byte_order_of(data):
            self.session, self.address = struct.unpack_from("<H" if data[0] == 0x54 else ">H", data, 14)[0], source
        self.node.receive(t, data, source)

    def due(self, t: float) -> list[tuple[tuple, bytes]]:
        if self.mode == "echo-only":
            out, self.echo = getattr(self, "echo", []), []
            return out
        out = self.node.due(t)
        mine = [(a, d) for a, d in out if a == self.address]
        if self.mode == "deep-nesting" and t >= self.next_deep and self.address is not None:
            self.next_deep = t + 1.0
            out.append((self.address, nested_frame(300, dst=self.session)))
        elif self.mode == "flood" and not self.flooded and t > 3.0 and any(self._reply(d) for _, d in mine):
            self.flooded = True
            beat = codec.encode(self.node.defs, {"abbrev": "Heartbeat", "header": {
                "timestamp": 1.7e9, "src": self.node.system, "src_ent": 0, "dst": 0xFFFF, "dst_ent": 0xFF}, "fields": {}})
            out = [(self.address, beat)] * 5000 + out
        impostor = []
        if self.mode in ("impostor-announce", "impostor-replies") and not self.impersonated and t > 1.0 \
                and any(self._reply(d) for _, d in mine):
            self.impersonated, self.redirect_until = True, t + REDIRECTED
            impostor = [(self.address, self._impostor(t))]
        if t < self.redirect_until:  # the session's replies go to the other run
            out = [(a, d) for a, d in out if a != self.address or not self._reply(d)]
        return out + impostor

    def _reply(self, data: bytes) -> bool:
        """Whether a frame the node sends is a reply (not its heartbeat or announce)."""
        (mgid,) = struct.unpack_from("<H", data, 2)
        return mgid not in (150, 151)

    def _impostor(self, t: float) -> bytes:
        header = {"timestamp": 1.7e9 + t, "src": self.session, "src_ent": 0, "dst": 0, "dst_ent": 0xFF}
        if self.mode == "impostor-announce":  # what the other run announces, heard on the session's discovery port
            fields = {"sys_name": "imc-conformance", "sys_type": 0, "owner": 0xFFFF, "lat": 0.0, "lon": 0.0,
                      "height": 0.0, "services": "imc+udp://127.0.0.1:7777/"}
            return codec.encode(self.node.defs, {"abbrev": "Announce", "header": header, "fields": fields})
        header.update(src=self.node.system, dst=self.session)  # a reply to the other run's request
        fields = {"req_id": 40000, "status": 3, "text": ""}
        return codec.encode(self.node.defs, {"abbrev": "IridiumTxStatus", "header": header, "fields": fields})
