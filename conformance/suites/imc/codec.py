"""Sans-IO reference codec for IMC frames, generic over the definitions.

``encode`` turns a message in the corpus's decoded form into a frame in either byte order;
``decode`` checks a frame in DUNE's order (header length, sync, size, CRC, id, fields) and raises
``FrameError`` naming the broken rule and the byte offset. ``layout`` names the bytes of a frame. Inline
messages are followed to ``NESTING_LIMIT`` levels both ways: a frame nested deeper is ``NotJudged`` (an
input cannot drive the recursion), a message nested deeper is refused.
"""

from __future__ import annotations

import struct

from ...kinds.vector import Span
from ...kinds.vector.errors import EncodeError, FrameError, NotJudged
from ...limits import NESTING_LIMIT
from .crc16 import crc16
from .definitions import SCALAR_FORMATS, Definitions, FieldDef, MessageDef
from .unpackers import Irregular, unpackers_of
from ...kinds.vector.floats import float_from_bits, float_to_bits
from .values import raw_bytes, text_bytes, text_value

HEADER_SIZE = 20
FOOTER_SIZE = 2
ORDERS = {"le": "<", "be": ">"}
HEADER_LAYOUT = ((0, 2, "sync", "uint16_t"), (2, 2, "mgid", "uint16_t"), (4, 2, "size", "uint16_t"),
                 (6, 8, "timestamp", "fp64_t"), (14, 2, "src", "uint16_t"), (16, 1, "src_ent", "uint8_t"),
                 (17, 2, "dst", "uint16_t"), (19, 1, "dst_ent", "uint8_t"))


def byte_order_of(frame: bytes) -> str | None:
    head = frame[:2]
    return {b"\x54\xfe": "le", b"\xfe\x54": "be"}.get(head)


# ---------------------------------------------------------------- encoding

def encode(defs: Definitions, message: dict, byte_order: str = "le") -> bytes:
    """The frame of ``message`` (decoded form) in ``byte_order``; raises EncodeError."""
    e = ORDERS[byte_order]
    mdef = _message_def(defs, message.get("abbrev"))
    payload = encode_payload(defs, mdef, message.get("fields", {}), e)
    if len(payload) > defs.max_payload:
        raise EncodeError("size-limit", f"payload of {len(payload)} bytes exceeds {defs.max_payload}")
    header = dict(defs.header_defaults, **message.get("header", {}))
    try:
        head = struct.pack(e + "HHH", defs.sync, mdef.id, len(payload)) + struct.pack(
            e + "Q", float_to_bits(header["timestamp"], 8)
        ) + struct.pack(e + "HBHB", header["src"], header["src_ent"], header["dst"], header["dst_ent"])
    except (struct.error, ValueError, TypeError) as exc:
        raise EncodeError("value-out-of-type", f"header: {exc}") from exc
    body = head + payload
    return body + struct.pack(e + "H", crc16(body))


def encode_payload(defs: Definitions, mdef: MessageDef, fields: dict, e: str, depth: int = 0) -> bytes:
    unknown = set(fields) - {f.abbrev for f in mdef.fields}
    if unknown:
        raise EncodeError("unknown-field", f"{mdef.abbrev} has no field {sorted(unknown)[0]!r}")
    out = bytearray()
    for f in mdef.fields:
        if f.abbrev not in fields:
            raise EncodeError("missing-field", f"{mdef.abbrev}.{f.abbrev} is missing")
        out += encode_field(defs, mdef, f, fields[f.abbrev], e, depth)
    return bytes(out)


def encode_field(defs: Definitions, mdef: MessageDef, f: FieldDef, value, e: str, depth: int = 0) -> bytes:
    where = f"{mdef.abbrev}.{f.abbrev}"
    try:
        if f.is_float:
            return struct.pack(e + ("I" if f.size == 4 else "Q"), float_to_bits(value, f.size))
        if f.is_int:
            lo, hi = f.int_bounds
            if isinstance(value, bool) or not isinstance(value, int):
                raise EncodeError("value-type", f"{where}: {value!r} is not an integer")
            if not lo <= value <= hi:
                raise EncodeError("value-out-of-type", f"{where}: {value} does not fit {f.type} [{lo}, {hi}]")
            return struct.pack(e + SCALAR_FORMATS[f.type], value)
        if f.type in ("plaintext", "rawdata"):
            data = text_bytes(value) if f.type == "plaintext" else raw_bytes(value)
            if len(data) > 0xFFFF:
                raise EncodeError("size-limit", f"{where}: {len(data)} bytes exceed a u16 length")
            return struct.pack(e + "H", len(data)) + data
        if f.type == "message":
            return _encode_inline(defs, value, e, where, depth)
        if value is None or not isinstance(value, list):
            raise EncodeError("value-type", f"{where}: a message-list must be an array")
        if len(value) > 0xFFFF:
            raise EncodeError("size-limit", f"{where}: {len(value)} elements exceed a u16 count")
        return struct.pack(e + "H", len(value)) + b"".join(_encode_inline(defs, v, e, where, depth) for v in value)
    except ValueError as exc:
        if isinstance(exc, EncodeError):
            raise
        raise EncodeError("value-type", f"{where}: {exc}") from exc


def _encode_inline(defs: Definitions, value, e: str, where: str, depth: int) -> bytes:
    if value is None:
        return struct.pack(e + "H", defs.null_id)
    if not isinstance(value, dict):
        raise EncodeError("value-type", f"{where}: an inline message must be an object or null")
    if depth >= NESTING_LIMIT:
        raise EncodeError("value-type", f"{where}: inline messages nested deeper than {NESTING_LIMIT} levels")
    inner = _message_def(defs, value.get("abbrev"))
    return struct.pack(e + "H", inner.id) + encode_payload(defs, inner, value.get("fields", {}), e, depth + 1)


def _message_def(defs: Definitions, abbrev) -> MessageDef:
    try:
        return defs.by_abbrev[abbrev]
    except (KeyError, TypeError):
        raise EncodeError("unknown-message", f"unknown message {abbrev!r}") from None


# ---------------------------------------------------------------- decoding

def decode(defs: Definitions, frame: bytes, spans: list[Span] | None = None) -> dict:
    """The decoded form of ``frame``; raises FrameError. Appends the frame's byte map to ``spans``."""
    n = len(frame)
    if n < HEADER_SIZE:
        raise FrameError("header-truncated", n, f"{n} bytes cannot hold the {HEADER_SIZE}-byte header")
    order = byte_order_of(frame)
    if order is None:
        raise FrameError("sync", 0, f"synchronization bytes {frame[:2].hex()} are neither 54fe nor fe54")
    e = ORDERS[order]
    _, mgid, size = struct.unpack_from(e + "HHH", frame)
    if size > defs.max_payload:
        raise FrameError("size-limit", 4, f"size {size} exceeds the largest payload {defs.max_payload}")
    if n < HEADER_SIZE + size + FOOTER_SIZE:
        raise FrameError("size-exceeds-data", n, f"size {size} needs {HEADER_SIZE + size + FOOTER_SIZE} bytes, got {n}")
    end = HEADER_SIZE + size
    (stored,) = struct.unpack_from(e + "H", frame, end)
    computed = crc16(frame[:end])
    if stored != computed:
        raise FrameError("crc", end, f"stored CRC {stored:04x}, computed {computed:04x}")
    mdef = defs.by_id.get(mgid)
    if mdef is None:
        raise FrameError("unknown-id", 2, f"message id {mgid} is not defined")
    ts_bits, src, src_ent, dst, dst_ent = struct.unpack_from(e + "QHBHB", frame, 6)
    if spans is not None:
        spans += [Span(start, start + size_, f"header.{name}", type_, "header") for start, size_, name, type_ in HEADER_LAYOUT]
        spans.append(Span(end, end + 2, "footer.crc16", "uint16_t", "footer"))
    fields = None
    if spans is None:
        try:
            fields = unpackers_of(defs).fields(mdef, frame, e, HEADER_SIZE, end)[0]
        except Irregular:  # the reader names what is wrong
            pass
    if fields is None:
        fields = _Reader(defs, frame, e, end, spans).fields(mdef, HEADER_SIZE, mdef.abbrev)
    header = {"timestamp": float_from_bits(ts_bits, 8), "src": src, "src_ent": src_ent, "dst": dst, "dst_ent": dst_ent}
    return {"abbrev": mdef.abbrev, "header": header, "fields": fields}


def layout(defs: Definitions, frame: bytes) -> list[Span]:
    """The byte map of a frame the codec can decode (header, every field, footer), in offset order."""
    spans: list[Span] = []
    decode(defs, frame, spans)
    return sorted(spans, key=lambda s: (s.start, s.end))


class _Reader:
    def __init__(self, defs: Definitions, frame: bytes, e: str, end: int, spans: list[Span] | None):
        self.defs, self.frame, self.e, self.end, self.spans = defs, frame, e, end, spans
        self.pos = HEADER_SIZE
        self.depth = 0

    def _take(self, count: int, rule: str, what: str, role: str | None = None) -> int:
        start = self.pos
        if start + count > self.end:
            raise FrameError(rule, start, f"{what} needs {count} bytes, {self.end - start} left in the payload", role)
        self.pos += count
        return start

    def _mark(self, start: int, path: str, type_: str, role: str = "value") -> None:
        if self.spans is not None:
            self.spans.append(Span(start, self.pos, path, type_, role))

    def _u16(self, rule: str, what: str, path: str, role: str) -> int:
        start = self._take(2, rule, what, role)
        self._mark(start, path, "uint16_t", role)
        return struct.unpack_from(self.e + "H", self.frame, start)[0]

    def fields(self, mdef: MessageDef, _start: int, path: str) -> dict:
        return {f.abbrev: self.field(f, f"{path}.{f.abbrev}") for f in mdef.fields}

    def field(self, f: FieldDef, path: str):
        if f.is_scalar:
            start = self._take(f.size, "field-overrun", path)
            self._mark(start, path, f.type)
            if f.is_float:
                bits = struct.unpack_from(self.e + ("I" if f.size == 4 else "Q"), self.frame, start)[0]
                return float_from_bits(bits, f.size)
            return struct.unpack_from(self.e + SCALAR_FORMATS[f.type], self.frame, start)[0]
        if f.type in ("plaintext", "rawdata"):
            length = self._u16("field-overrun", f"{path} length", path + ".length", "length")
            start = self._take(length, "length-overrun", f"{path} ({length} bytes)")
            self._mark(start, path, f.type)
            data = self.frame[start:self.pos]
            return text_value(data) if f.type == "plaintext" else data.hex()
        if f.type == "message":
            return self.inline(path, "field-overrun")
        count = self._u16("field-overrun", f"{path} count", path + ".count", "count")
        return [self.inline(f"{path}[{i}]", "list-count-overrun") for i in range(count)]

    def inline(self, path: str, rule: str):
        id_start = self.pos
        mgid = self._u16(rule, f"{path} message id", path + ".id", "id")
        if mgid == self.defs.null_id:
            return None
        inner = self.defs.by_id.get(mgid)
        if inner is None:
            raise FrameError("unknown-inline-id", id_start, f"{path} holds unknown message id {mgid}")
        if self.depth >= NESTING_LIMIT:
            raise NotJudged("nested-too-deep", id_start, f"inline messages nested deeper than {NESTING_LIMIT} levels, "
                                                         "the reference codec's bound: not judged")
        self.depth += 1
        fields = self.fields(inner, self.pos, f"{path}.{inner.abbrev}")
        self.depth -= 1
        return {"abbrev": inner.abbrev, "fields": fields}
