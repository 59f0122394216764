"""Between scapy packets and the corpus's decoded form of a message (as ``codec.decode`` gives it)."""

from __future__ import annotations

from scapy.packet import Packet

from .frame import HEADER_FIELDS, IMC
from .messages import Message, message_class


def to_decoded(pkt: Packet) -> dict:
    """The decoded form of the IMC frame in ``pkt``: {"abbrev", "header", "fields"}. The frame's size and
    CRC are not checked; ValueError if its message did not dissect."""
    frame = pkt if isinstance(pkt, IMC) else pkt[IMC]
    message = frame.message
    if not isinstance(message, Message):
        raise ValueError(f"the frame's message did not dissect: {message!r}")
    header = {name: frame.get_field(name).i2d(frame.getfieldval(name)) for name in HEADER_FIELDS}
    return {"abbrev": message.definition.abbrev, "header": header, "fields": message.decoded_fields()}


def from_decoded(message: dict, byte_order: str = "le") -> IMC:
    """The IMC frame of ``message`` (decoded form) in ``byte_order`` (``le`` or ``be``); its size and CRC
    are computed when it is built. Header fields and fields not given keep their defaults."""
    body = message_class(message["abbrev"]).from_decoded_fields(message.get("fields", {}))
    return IMC(sync=byte_order, message=body, **message.get("header", {}))
