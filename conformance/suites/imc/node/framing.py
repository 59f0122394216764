"""How the reference node builds, names and schedules the frames it sends: a reply to a request (to its
requester, lost or repeated as the link's model says), a frame at a later time, and the definitions' names for
values."""

from __future__ import annotations

import heapq
import struct

from .. import codec
from ..crc16 import crc16
from ..values import text_bytes

PROCESSING = 0.005  # s the node takes to answer anything
UNKNOWN_SYSTEM, UNKNOWN_ENTITY = 0xFFFF, 0xFF


class Framing:
    """The reference node's sending of frames (a mixin of ``ReferenceNode``)."""

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

    def _v(self, message: str, path: str, name: str):
        try:
            return self.wire.resolve(message, path, name, self.edition)
        except KeyError:
            return None

    def _name(self, message: str, path: str, value: int) -> str | None:
        for v in self.defs[message].field(path).enum_values:
            if v.value == value and v.in_edition(self.edition):
                return v.abbrev
        return None


def text_of(value) -> str:
    """A plaintext field as text (bytes that are not UTF-8 replaced), whatever its decoded form."""
    return text_bytes(value).decode("utf-8", "replace")
