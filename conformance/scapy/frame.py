"""The IMC frame as a scapy layer: the header, the message, the CRC-16 footer, in the byte order its sync
bytes give. Only the first frame of the data counts; the bytes after it are padding."""

from __future__ import annotations

import struct

from scapy.compat import raw
from scapy.config import conf
from scapy.fields import Field, LEShortEnumField, _FieldContainer
from scapy.packet import Packet

from ..suites import load_suite
from ..suites.imc.codec import FOOTER_SIZE, HEADER_SIZE, byte_order_of
from ..suites.imc.crc16 import crc16
from .byteorder import packing, prefix
from .fields import Checksum, Enum, Float, Number
from .messages import Message, definitions, message_class

_DEFS = load_suite("imc").defs  # the frame's constants (sync, header defaults) are the same in any IMC definitions
SYNC = _DEFS.sync  # 0xFE54: bytes 54 FE, little-endian
SWAPPED_SYNC = int.from_bytes(SYNC.to_bytes(2, "big"), "little")  # 0x54FE: bytes FE 54, big-endian
HEADER_FIELDS = ("timestamp", "src", "src_ent", "dst", "dst_ent")  # those of the decoded form


class Cut(_FieldContainer):
    """A frame field whose value is None when the data ends within it, so that a cut frame dissects."""

    __slots__ = ()

    def __init__(self, fld: Field):
        self.fld = fld

    def getfield(self, pkt, s: bytes):
        try:
            return self.fld.getfield(pkt, s)
        except struct.error:
            return b"", None


class MessageId(Enum):
    """The frame's message id, shown by abbreviation; None stands for the id of the frame's message."""

    def i2m(self, pkt, x) -> int:
        if x is None:
            if not isinstance(pkt.message, Message):
                raise ValueError("IMC: give mgid, the frame's message is not an IMC message")
            x = pkt.message.definition.id
        return super().i2m(pkt, x)


class FrameMessage(Field):
    """The frame's message: ``size`` bytes dissected as the message ``mgid`` names. An unknown id, a
    payload that does not dissect, or one the data cuts short is kept as Raw bytes (None when empty)."""

    holds_packets = 1

    def __init__(self, name: str):
        Field.__init__(self, name, None)

    def addfield(self, pkt, s: bytes, val) -> bytes:
        return s + (b"" if val is None else raw(val))

    def getfield(self, pkt, s: bytes):
        size = pkt.size or 0
        return s[size:], self.m2i(pkt, s[:size])

    def m2i(self, pkt, data: bytes):
        if len(data) == pkt.size and pkt.mgid in definitions().by_id:
            message = message_class(pkt.mgid)()
            try:
                message.dissect(data)
                return message
            except Exception:
                if conf.debug_dissector:
                    raise
        return conf.raw_layer(data) if data else None


MESSAGE_ID = MessageId("mgid", None, "H", {})


def name_messages(defs) -> None:
    """Show (and accept) message ids by the abbreviations of ``defs``."""
    for table, items in ((MESSAGE_ID.i2s, ((m.id, m.abbrev) for m in defs.messages)),
                         (MESSAGE_ID.s2i, ((m.abbrev, m.id) for m in defs.messages))):
        table.clear()
        table.update(items)


name_messages(_DEFS)


class IMC(Packet):
    """An IMC frame. ``sync`` is ``le`` (0xFE54, bytes 54 FE) or ``be`` (0x54FE read little-endian, bytes
    FE 54) and sets the byte order of everything else; ``mgid``, ``size`` and ``crc16`` left None are
    computed when the frame is built, given values are kept."""

    name = "IMC"
    fields_desc = [
        Cut(LEShortEnumField("sync", SYNC, {SYNC: "le", SWAPPED_SYNC: "be"})),
        Cut(MESSAGE_ID),
        Cut(Number("size", None, "H")),
        Cut(Float("timestamp", _DEFS.header_defaults["timestamp"], 8, "s")),
        Cut(Number("src", _DEFS.header_defaults["src"], "H")),
        Cut(Number("src_ent", _DEFS.header_defaults["src_ent"], "B")),
        Cut(Number("dst", _DEFS.header_defaults["dst"], "H")),
        Cut(Number("dst_ent", _DEFS.header_defaults["dst_ent"], "B")),
        FrameMessage("message"),
        Cut(Checksum("crc16", None, "H")),
    ]

    @property
    def byte_order(self) -> str:
        """``le`` or ``be``, as ``sync`` says (a sync that is neither reads as ``le``)."""
        return "be" if self.sync == SWAPPED_SYNC else "le"

    def do_dissect(self, s: bytes) -> bytes:
        with packing(byte_order_of(s) or "le"):
            return super().do_dissect(s)

    def do_build(self) -> bytes:
        with packing(self.byte_order):
            return super().do_build()

    def post_build(self, pkt: bytes, pay: bytes) -> bytes:
        if self.size is None:
            pkt = pkt[:4] + struct.pack(prefix() + "H", len(pkt) - HEADER_SIZE - FOOTER_SIZE) + pkt[6:]
        if self.crc16 is None:
            pkt = pkt[:-2] + struct.pack(prefix() + "H", crc16(pkt[:-2]))
        return pkt + pay

    def extract_padding(self, s: bytes) -> tuple[bytes, bytes]:
        return b"", s

    def mysummary(self) -> str:
        return self.sprintf("IMC %mgid% %src%:%src_ent% > %dst%:%dst_ent%")
