"""The baselines every IMC mutant departs from: ``Reference`` wraps the reference codec as a library adapter;
``Stepwise`` rebuilds its decoder from the codec's pieces, one method per check in DUNE's order, so that a mutant
overrides exactly the check or the reading it gets wrong. With the helpers the buggy encoders share."""

from __future__ import annotations

import dataclasses
import functools
import struct

from .. import codec
from ....adapter_api import Rejected
from ..codec import FOOTER_SIZE, HEADER_SIZE, ORDERS, EncodeError, FrameError
from ..crc16 import crc16
from ..definitions import MessageDef
from ....kinds.vector.floats import float_from_bits


MIN_NORMAL = {4: 2.0 ** -126, 8: 2.0 ** -1022}
cached_crc16 = functools.cache(crc16)  # every mutant re-checks the same frames: keeps the runs fast


def with_footer(body: bytes, e: str, crc=crc16) -> bytes:
    """``body`` (header and payload) followed by its CRC, packed with ``e``."""
    return body + struct.pack(e + "H", crc(body))


def rewrite_prefixes(defs, frame: bytes, byte_order: str, pick, change) -> bytes:
    """``frame`` with every u16 prefix span that ``pick(span, types)`` selects replaced by ``change(value)``.

    ``types`` maps each span path to its wire type, so that a length prefix (``X.length``) can be told
    to belong to a plaintext or a rawdata ``X``. The CRC is recomputed, as the buggy encoder would.
    """
    e = ORDERS[byte_order]
    spans = codec.layout(defs, frame)
    types = {s.path: s.type for s in spans}
    body = bytearray(frame[:-FOOTER_SIZE])
    for s in spans:
        if pick(s, types):
            (value,) = struct.unpack_from(e + "H", body, s.start)
            struct.pack_into(e + "H", body, s.start, change(value) & 0xFFFF)
    return with_footer(bytes(body), e)


def retype(defs, pick, new_type: str):
    """The definitions with every field that ``pick(message, field)`` selects given ``new_type`` (a drifted
    definition, as a generator fed an edited IMC.xml produces)."""
    messages = tuple(dataclasses.replace(m, fields=tuple(dataclasses.replace(f, type=new_type) if pick(m, f) else f
                                                         for f in m.fields)) for m in defs.messages)
    return dataclasses.replace(defs, messages=messages)


class Reference:
    """The reference codec as a library adapter: correct, the baseline every mutant departs from."""

    name = "reference"
    byte_orders = ("le", "be")

    def __init__(self, defs):
        self.defs = defs

    def hello(self) -> dict:
        return {"implementation": f"mutant {self.name}", "suites": ["imc"], "byte_orders": list(self.byte_orders)}

    def encode(self, suite: str, message: dict, byte_order: str) -> bytes:
        try:
            return self.encode_frame(message, byte_order)
        except EncodeError as exc:
            raise Rejected(exc.detail, rule=exc.rule) from exc

    def decode(self, suite: str, frame: bytes) -> dict:
        try:
            return self.decode_frame(frame)
        except FrameError as exc:
            raise Rejected(exc.detail, rule=exc.rule) from exc

    def encode_frame(self, message: dict, byte_order: str) -> bytes:
        return codec.encode(self.defs, message, byte_order)

    def decode_frame(self, frame: bytes) -> dict:
        return codec.decode(self.defs, frame)


class Stepwise(Reference):
    """The reference decoder rebuilt check by check (correct too: the base of the decoding mutants)."""

    name = "stepwise"
    Reader = codec._Reader

    def decode_frame(self, frame: bytes) -> dict:
        frame = self.check_length(frame)
        e = self.check_sync(frame)
        _, mgid, size = struct.unpack_from(e + "HHH", frame)
        self.check_size(size)
        end = self.payload_end(frame, size)
        self.check_crc(frame, end, e)
        mdef = self.message_def(mgid)
        fields = self.Reader(self.defs, frame, self.payload_order(e), end, None).fields(mdef, HEADER_SIZE, mdef.abbrev)
        return {"abbrev": mdef.abbrev, "header": self.header(frame, e), "fields": fields}

    def check_length(self, frame: bytes) -> bytes:
        if len(frame) < HEADER_SIZE:
            raise FrameError("header-truncated", len(frame), f"{len(frame)} bytes cannot hold the header")
        return frame

    def check_sync(self, frame: bytes) -> str:
        order = codec.byte_order_of(frame)
        if order is None:
            raise FrameError("sync", 0, f"synchronization bytes {frame[:2].hex()}")
        return ORDERS[order]

    def check_size(self, size: int) -> None:
        """DUNE's frame cap (rule size-limit) is a practice the reference does not hold."""

    def payload_end(self, frame: bytes, size: int) -> int:
        if len(frame) < HEADER_SIZE + size + FOOTER_SIZE:
            raise FrameError("size-exceeds-data", len(frame), f"size {size} needs more than {len(frame)} bytes")
        return HEADER_SIZE + size

    def crc(self, body: bytes) -> int:
        return cached_crc16(body)

    def crc_order(self, e: str) -> str:
        return e

    def check_crc(self, frame: bytes, end: int, e: str) -> None:
        stored, computed = frame[end:end + FOOTER_SIZE], struct.pack(self.crc_order(e) + "H", self.crc(frame[:end]))
        if stored != computed:
            raise FrameError("crc", end, f"stored CRC {stored.hex()}, computed {computed.hex()}")

    def message_def(self, mgid: int) -> MessageDef:
        mdef = self.defs.by_id.get(mgid)
        if mdef is None:
            raise FrameError("unknown-id", 2, f"message id {mgid} is not defined")
        return mdef

    def payload_order(self, e: str) -> str:
        return e

    def header(self, frame: bytes, e: str) -> dict:
        ts_bits, src, src_ent, dst, dst_ent = struct.unpack_from(e + "QHBHB", frame, 6)
        return {"timestamp": float_from_bits(ts_bits, 8), "src": src, "src_ent": src_ent, "dst": dst, "dst_ent": dst_ent}
