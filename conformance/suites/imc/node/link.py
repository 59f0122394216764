"""What the reference node does to the link beside answering: the seeded loss of an idempotent exchange's
requests and replies (never more than ``LOSS_RUN`` copies of one message), and a vehicle's other traffic
(vehicle-traffic)."""

from __future__ import annotations

import struct

from ..crc16 import crc16
from .framing import UNKNOWN_ENTITY, UNKNOWN_SYSTEM

LOSS_RUN = 2  # at most this many copies of one message dropped by ``loss``
MAX_LOSS_KEYS = 4096  # messages whose drops are counted at once (then the count starts again)
# vehicle-traffic: (message id, payload, byte order, every how many 0.2 s ticks) of messages outside the seeds, as a
# DUNE vehicle streams them (IMC.xml 5.4: EstimatedState's 20 fields, EntityState, CpuUsage, EulerAngles, Temperature),
# and an id no IMC.xml defines (999: a newer or private message); with them a HistoricData (``_historic_traffic``)
TRAFFIC_TICK = 0.2
TRAFFIC = ((350, bytes(88), "<", 1), (1, bytes([1, 0]) + struct.pack("<H", 6) + b"Active", "<", 1),
           (7, bytes([12]), "<", 1), (254, bytes(40), "<", 5), (263, struct.pack(">f", 14.5), ">", 5),
           (999, b"\x01\x02\x03", "<", 5))


class Link:
    """The reference node's loss model and other traffic (a mixin of ``ReferenceNode``)."""

    def _lost(self, message: dict, reply: bool = False) -> bool:
        """Drop the first copy of each idempotent request (loses-first-copy: the requester must resend it), or drop
        at random (``loss``) a request or reply of an idempotent exchange; never more than ``LOSS_RUN``
        copies of one message (a scenario resends a few times: a link that loses every try is a dead link, not a
        lossy one; counted per message, not per kind, as other traffic between two tries must not reset it)."""
        targeted = self.variant == "loses-first-copy"  # a loss certain for a request's first copy, of no reply
        if (reply if targeted else not self.loss) or not self._idempotent(message, reply):
            return False
        key = (message["abbrev"], repr(message["fields"]))  # a resent request, or its reply, is the same message
        dropped = self.loss_runs.get(key, 0)
        lost = dropped < (1 if targeted else LOSS_RUN) and (targeted or self.rng.random() < self.loss)
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
