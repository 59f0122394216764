"""Sans-IO reference codec for IMC frames, generic over the definitions.

``encode`` turns a message in the corpus's decoded form into a frame in either byte order;
``decode`` checks a frame in DUNE's order (header length, sync, size, CRC, id, fields) and raises
``FrameError`` naming the broken rule and the byte offset. ``layout`` names the bytes of a frame. Inline
messages are followed to ``NESTING_LIMIT`` levels both ways: a frame nested deeper is ``NotJudged`` (an
input cannot drive the recursion), a message nested deeper is refused.

Every rule has a switch. ``off``: rules not checked, each replaced by what a reader without that check does
(``LENIENT``): the oracle of ``generate --check`` proves with it that an invalid vector breaks exactly the rules
it names, and the per-rule mutants are the codec with one switch off. ``held``: rules of practice (rules.json
level "practice", e.g. DUNE's frame cap ``size-limit``) checked too; none is by default.

``elsewhere``: for judging traffic, where inline messages may be any of the protocol's (a HistoricSample holding an
EstimatedState): the definition of an inline id the definitions lack (the whole IMC.xml's), or why there is none. An inline message
read with it is framing checked only; an inline id no definition names makes the frame ``NotJudged`` (an inline message
carries no length: the bytes after its id cannot be placed), never ``unknown-inline-id``, which stays the rule of a
decoder given only the definitions (the corpus's).
"""

from __future__ import annotations

import struct
from collections.abc import Callable

from ...kinds.vector import Span
from ...kinds.vector.errors import EncodeError, FrameError, NotJudged
from ...limits import NESTING_LIMIT
from .crc16 import crc16
from .definitions import SCALAR_FORMATS, Definitions, FieldDef, MessageDef
from .unpackers import Irregular, unpackers_of
from ...kinds.vector.floats import float_from_bits, float_to_bits
from .values import raw_bytes, text_bytes, text_value

Elsewhere = Callable[[int], "MessageDef | str"]  # an inline id the definitions lack -> its definition, or why none
HEADER_SIZE = 20
FOOTER_SIZE = 2
ORDERS = {"le": "<", "be": ">"}
# What a reader does with each rule switched off (``off``): the one behaviour the oracle and the mutants share.
LENIENT = {
    "header-truncated": "a frame shorter than the header is padded with zero bytes to the header's 20",
    "sync": "a frame whose first two bytes name no byte order is read in the order whose size field fits its length",
    "size-exceeds-data": "the payload is what lies between the header and the last two bytes, taken as the CRC",
    "crc": "the footer is not compared with the CRC",
    "unknown-id": "an undefined or null message id is read as a message without fields",
    "field-overrun": "a field that does not fit the payload takes its empty value (0, empty, null)",
    "length-overrun": "a plaintext or rawdata length is clamped to the bytes left in the payload",
    "list-count-overrun": "a message-list ends at the payload's end, whatever its count claims",
    "unknown-inline-id": "an inline message or list element with an undefined id is read as null",
    "payload-overflow": "a length, count or size over 65535 is written modulo 65536",
}
NONE: frozenset[str] = frozenset()
HEADER_LAYOUT = ((0, 2, "sync", "uint16_t"), (2, 2, "mgid", "uint16_t"), (4, 2, "size", "uint16_t"),
                 (6, 8, "timestamp", "fp64_t"), (14, 2, "src", "uint16_t"), (16, 1, "src_ent", "uint8_t"),
                 (17, 2, "dst", "uint16_t"), (19, 1, "dst_ent", "uint8_t"))


def byte_order_of(frame: bytes) -> str | None:
    head = frame[:2]
    return {b"\x54\xfe": "le", b"\xfe\x54": "be"}.get(head)


# ---------------------------------------------------------------- encoding

def encode(defs: Definitions, message: dict, byte_order: str = "le", *, off: frozenset[str] = NONE,
           held: frozenset[str] = NONE) -> bytes:
    """The frame of ``message`` (decoded form) in ``byte_order``; raises EncodeError. ``off`` and ``held``: the
    rules switched off and the rules of practice held (see the module's docstring)."""
    e = ORDERS[byte_order]
    mdef = _message_def(defs, message.get("abbrev"))
    payload = encode_payload(defs, mdef, message.get("fields", {}), e, off=off)
    if len(payload) > 0xFFFF and "payload-overflow" not in off:
        raise EncodeError("payload-overflow", f"a payload of {len(payload)} bytes does not fit the u16 size field")
    if "size-limit" in held and len(payload) > defs.max_payload:
        raise EncodeError("size-limit", f"payload of {len(payload)} bytes exceeds {defs.max_payload}")
    header = dict(defs.header_defaults, **message.get("header", {}))
    try:
        head = struct.pack(e + "HHH", defs.sync, mdef.id, len(payload) & 0xFFFF) + struct.pack(
            e + "Q", float_to_bits(header["timestamp"], 8)
        ) + struct.pack(e + "HBHB", header["src"], header["src_ent"], header["dst"], header["dst_ent"])
    except (struct.error, ValueError, TypeError) as exc:
        raise EncodeError("value-out-of-type", f"header: {exc}") from exc
    body = head + payload
    return body + struct.pack(e + "H", crc16(body))


def encode_payload(defs: Definitions, mdef: MessageDef, fields: dict, e: str, depth: int = 0, *,
                   off: frozenset[str] = NONE) -> bytes:
    unknown = set(fields) - {f.abbrev for f in mdef.fields}
    if unknown:
        raise EncodeError("unknown-field", f"{mdef.abbrev} has no field {sorted(unknown)[0]!r}")
    out = bytearray()
    for f in mdef.fields:
        if f.abbrev not in fields:
            raise EncodeError("missing-field", f"{mdef.abbrev}.{f.abbrev} is missing")
        out += encode_field(defs, mdef, f, fields[f.abbrev], e, depth, off=off)
    return bytes(out)


def _u16_prefix(e: str, count: int, where: str, what: str, off: frozenset[str]) -> bytes:
    """A length or count prefix; refused (payload-overflow) where it cannot be carried in 16 bits."""
    if count > 0xFFFF and "payload-overflow" not in off:
        raise EncodeError("payload-overflow", f"{where}: {count} {what} exceed a u16 {'count' if what == 'elements' else 'length'}")
    return struct.pack(e + "H", count & 0xFFFF)


def encode_field(defs: Definitions, mdef: MessageDef, f: FieldDef, value, e: str, depth: int = 0, *,
                 off: frozenset[str] = NONE) -> bytes:
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
            return _u16_prefix(e, len(data), where, "bytes", off) + data
        if f.type == "message":
            return _encode_inline(defs, value, e, where, depth, off)
        if value is None or not isinstance(value, list):
            raise EncodeError("value-type", f"{where}: a message-list must be an array")
        return _u16_prefix(e, len(value), where, "elements", off) + b"".join(
            _encode_inline(defs, v, e, where, depth, off) for v in value)
    except ValueError as exc:
        if isinstance(exc, EncodeError):
            raise
        raise EncodeError("value-type", f"{where}: {exc}") from exc


def _encode_inline(defs: Definitions, value, e: str, where: str, depth: int, off: frozenset[str]) -> bytes:
    if value is None:
        return struct.pack(e + "H", defs.null_id)
    if not isinstance(value, dict):
        raise EncodeError("value-type", f"{where}: an inline message must be an object or null")
    if depth >= NESTING_LIMIT:
        raise EncodeError("value-type", f"{where}: inline messages nested deeper than {NESTING_LIMIT} levels")
    inner = _message_def(defs, value.get("abbrev"))
    return struct.pack(e + "H", inner.id) + encode_payload(defs, inner, value.get("fields", {}), e, depth + 1, off=off)


def _message_def(defs: Definitions, abbrev) -> MessageDef:
    try:
        return defs.by_abbrev[abbrev]
    except (KeyError, TypeError):
        raise EncodeError("unknown-message", f"unknown message {abbrev!r}") from None


# ---------------------------------------------------------------- decoding

def decode(defs: Definitions, frame: bytes, spans: list[Span] | None = None, *, off: frozenset[str] = NONE,
           held: frozenset[str] = NONE, elsewhere: Elsewhere | None = None) -> dict:
    """The decoded form of ``frame``; raises FrameError. Appends the frame's byte map to ``spans``. ``off``,
    ``held`` and ``elsewhere``: the rules switched off, the rules of practice held and where an inline id the
    definitions lack is looked up (see the module's docstring)."""
    n = len(frame)
    if n < HEADER_SIZE:
        if "header-truncated" not in off:
            raise FrameError("header-truncated", n, f"{n} bytes cannot hold the {HEADER_SIZE}-byte header")
        frame, n = frame.ljust(HEADER_SIZE, b"\0"), HEADER_SIZE
    order = byte_order_of(frame)
    if order is None:
        if "sync" not in off:
            raise FrameError("sync", 0, f"synchronization bytes {frame[:2].hex()} are neither 54fe nor fe54")
        order = _order_by_size(frame)
    e = ORDERS[order]
    _, mgid, size = struct.unpack_from(e + "HHH", frame)
    if "size-limit" in held and size > defs.max_payload:
        raise FrameError("size-limit", 4, f"size {size} exceeds the largest payload {defs.max_payload}")
    end = HEADER_SIZE + size
    if n < end + FOOTER_SIZE:
        if "size-exceeds-data" not in off:
            raise FrameError("size-exceeds-data", n, f"size {size} needs {end + FOOTER_SIZE} bytes, got {n}")
        end = max(HEADER_SIZE, n - FOOTER_SIZE)
    if "crc" not in off:
        footer = frame[end:end + FOOTER_SIZE]
        stored = struct.unpack(e + "H", footer)[0] if len(footer) == FOOTER_SIZE else None
        computed = crc16(frame[:end])
        if stored != computed:
            shown = "absent" if stored is None else f"{stored:04x}"
            raise FrameError("crc", end, f"stored CRC {shown}, computed {computed:04x}")
    mdef = defs.by_id.get(mgid)
    if mdef is None:
        if "unknown-id" not in off:
            raise FrameError("unknown-id", 2, f"message id {mgid} is not defined")
        mdef = MessageDef(id=mgid, abbrev=f"Unknown{mgid}", name="Unknown", clause="", fields=(), min_payload=0)
    ts_bits, src, src_ent, dst, dst_ent = struct.unpack_from(e + "QHBHB", frame, 6)
    if spans is not None:
        spans += [Span(start, start + size_, f"header.{name}", type_, "header") for start, size_, name, type_ in HEADER_LAYOUT]
        spans.append(Span(end, end + 2, "footer.crc16", "uint16_t", "footer"))
    fields = None
    if spans is None and not off:
        try:
            fields = unpackers_of(defs).fields(mdef, frame, e, HEADER_SIZE, end)[0]
        except Irregular:  # the reader names what is wrong
            pass
    if fields is None:
        fields = _Reader(defs, frame, e, end, spans, off, elsewhere).fields(mdef, HEADER_SIZE, mdef.abbrev)
    header = {"timestamp": float_from_bits(ts_bits, 8), "src": src, "src_ent": src_ent, "dst": dst, "dst_ent": dst_ent}
    return {"abbrev": mdef.abbrev, "header": header, "fields": fields}


def _order_by_size(frame: bytes) -> str:
    """The byte order in which the rest of a frame holds (sync switched off): its size field fits the data exactly and
    its footer is the CRC; failing that, one whose size fits exactly, else one whose frame the data holds; else LE."""
    n = len(frame)
    ends = {order: HEADER_SIZE + struct.unpack_from(ORDERS[order] + "H", frame, 4)[0] for order in ORDERS}
    exact = [o for o in ORDERS if ends[o] + FOOTER_SIZE == n]
    sound = [o for o in exact if struct.unpack_from(ORDERS[o] + "H", frame, ends[o])[0] == crc16(frame[:ends[o]])]
    return next(iter(sound + exact + [o for o in ORDERS if ends[o] + FOOTER_SIZE <= n]), "le")


def layout(defs: Definitions, frame: bytes) -> list[Span]:
    """The byte map of a frame the codec can decode (header, every field, footer), in offset order."""
    spans: list[Span] = []
    decode(defs, frame, spans)
    return sorted(spans, key=lambda s: (s.start, s.end))


class _Reader:
    def __init__(self, defs: Definitions, frame: bytes, e: str, end: int, spans: list[Span] | None,
                 off: frozenset[str] = NONE, elsewhere: Elsewhere | None = None):
        self.defs, self.frame, self.e, self.end, self.spans, self.off = defs, frame, e, end, spans, off
        self.elsewhere = elsewhere
        self.pos = HEADER_SIZE
        self.depth = 0

    def _take(self, count: int, rule: str, what: str, role: str | None = None) -> int:
        start = self.pos
        if start + count > self.end:
            if rule not in self.off:
                raise FrameError(rule, start, f"{what} needs {count} bytes, {self.end - start} left in the payload", role)
            if rule == "length-overrun":  # clamped to the bytes left
                count = self.end - start
            else:  # field-overrun: the missing bytes read as zeros (an empty value)
                missing = start + count - self.end
                self.frame = self.frame[:self.end] + bytes(missing) + self.frame[self.end:]
                self.end += missing
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
            if self.pos + 2 > self.end and "field-overrun" in self.off:
                return None  # a missing inline id: absent
            return self.inline(path, "field-overrun")
        count = self._u16("field-overrun", f"{path} count", path + ".count", "count")
        elements = []
        for i in range(count):
            if self.pos == self.end and "list-count-overrun" in self.off:
                break
            elements.append(self.inline(f"{path}[{i}]", "list-count-overrun"))
        return elements

    def inline(self, path: str, rule: str):
        id_start = self.pos
        mgid = self._u16(rule, f"{path} message id", path + ".id", "id")
        if mgid == self.defs.null_id:
            return None
        inner = self.defs.by_id.get(mgid)
        if inner is None and self.elsewhere is not None:
            inner = self.elsewhere(mgid)
            if isinstance(inner, str):
                raise NotJudged("inline-outside-definitions", id_start,
                                f"{path} holds message id {mgid} ({inner}): an inline message carries no length, so "
                                "the rest of the frame cannot be read: not judged")
        if inner is None:
            if "unknown-inline-id" in self.off:
                return None
            raise FrameError("unknown-inline-id", id_start, f"{path} holds unknown message id {mgid}")
        if self.depth >= NESTING_LIMIT:
            raise NotJudged("nested-too-deep", id_start, f"inline messages nested deeper than {NESTING_LIMIT} levels, "
                                                         "the reference codec's bound: not judged")
        self.depth += 1
        fields = self.fields(inner, self.pos, f"{path}.{inner.abbrev}")
        self.depth -= 1
        return {"abbrev": inner.abbrev, "fields": fields}
