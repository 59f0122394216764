"""Readers nobody here wrote: habits of real implementations, each caught by the corpus itself (``UNSEEN``)."""

from __future__ import annotations

import struct

from .. import codec
from ..codec import FOOTER_SIZE, HEADER_SIZE
from .base import Reference, Stepwise


# ---------------------------------------------------------------- readers nobody here wrote

class IgnoresSize(Stepwise):
    """Reads the fields on to the end of the data, never bounded by the size field (the CRC is checked where size says
    it is): a payload cut short is completed from the CRC and whatever follows it."""

    name = "ignores-size"

    def decode_frame(self, frame: bytes) -> dict:
        frame = self.check_length(frame)
        e = self.check_sync(frame)
        _, mgid, size = struct.unpack_from(e + "HHH", frame)
        end = self.payload_end(frame, size)
        self.check_crc(frame, end, e)
        mdef = self.message_def(mgid)
        fields = self.Reader(self.defs, frame, e, len(frame), None).fields(mdef, HEADER_SIZE, mdef.abbrev)
        return {"abbrev": mdef.abbrev, "header": self.header(frame, e), "fields": fields}


class CrcAtEndOfData(Stepwise):
    """Takes a datagram for exactly one frame: the CRC is its last two bytes, over everything before them (bytes after a
    frame are refused as a bad CRC, a frame whose size stops short of its footer is accepted)."""

    name = "crc-at-end-of-data"

    def check_crc(self, frame: bytes, end: int, e: str) -> None:
        super().check_crc(frame, len(frame) - FOOTER_SIZE, e)


class RestampsTimestamps(Reference):
    """Stamps every message it encodes with the time of sending (a fixed clock here), whatever timestamp it was
    given."""

    name = "restamps-timestamps"

    def encode_frame(self, message: dict, byte_order: str) -> bytes:
        return super().encode_frame(dict(message, header=dict(message["header"], timestamp=SENDING_TIME)), byte_order)


class RestampsZeroTimestamps(Reference):
    """Stamps a message it encodes with the time of sending when its timestamp is 0 (or -0.0): 'not stamped yet'."""

    name = "restamps-zero-timestamps"
    equivalent = ("IMC.xml: the timestamp is 'The time when the packet was sent, as seen by the packet dispatcher'; "
                  "whether 0 means a time or 'not stamped' is not said (class zero-timestamp)")

    def encode_frame(self, message: dict, byte_order: str) -> bytes:
        if message["header"].get("timestamp") == 0:
            message = dict(message, header=dict(message["header"], timestamp=SENDING_TIME))
        return super().encode_frame(message, byte_order)


class CrashesOnNullElement(Reference):
    """Encoding a message-list that holds a null element dereferences it: the encoder crashes."""

    name = "crashes-on-null-element"

    def encode_frame(self, message: dict, byte_order: str) -> bytes:
        if _null_elements(self.defs, message):
            raise AttributeError("'NoneType' object has no attribute 'serialize'")
        return super().encode_frame(message, byte_order)


class HoldsSizeLimit(Reference):
    """Holds DUNE's frame cap: refuses to decode or encode a frame over 65,535 bytes, naming size-limit."""

    name = "holds-size-limit"
    equivalent = "DUNE's cap is its own practice (rules.json size-limit, level practice): refusing is a permitted outcome"

    def decode_frame(self, frame: bytes) -> dict:
        return codec.decode(self.defs, frame, held=frozenset(("size-limit",)))

    def encode_frame(self, message: dict, byte_order: str) -> bytes:
        return codec.encode(self.defs, message, byte_order, held=frozenset(("size-limit",)))


SENDING_TIME = 1800000000.0  # the clock of the restamping mutants


def _null_elements(defs, message) -> bool:
    """Whether a message (or one inside it) has a message-list holding a null element (iteratively)."""
    stack = [message]
    while stack:
        m = stack.pop()
        mdef = defs.by_abbrev.get(m.get("abbrev")) if isinstance(m, dict) else None
        if mdef is None:
            continue
        for f in mdef.fields:
            value = m.get("fields", {}).get(f.abbrev)
            if f.type == "message-list" and isinstance(value, list):
                if any(v is None for v in value):
                    return True
                stack += value
            elif f.type == "message" and isinstance(value, dict):
                stack.append(value)
    return False
