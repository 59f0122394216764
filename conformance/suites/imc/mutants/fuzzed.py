"""More seeded bugs, added with the fuzzer (``NEW``): the corpus or the fuzzer catches each."""

from __future__ import annotations

import functools
import math
import struct

from .. import codec
from ..codec import FOOTER_SIZE, HEADER_SIZE, ORDERS, FrameError
from ..crc16 import crc16
from ....kinds.vector.floats import float_from_bits
from ..values import text_bytes, text_value
from .base import Reference, Stepwise, cached_crc16, retype, rewrite_prefixes, with_footer


# ---------------------------------------------------------------- more seeded bugs (the fuzzing issue's set)

class ValueMutant(Stepwise):
    """Base of the decoders that alter decoded field values: ``change(field, value)``."""

    def __init__(self, defs):
        super().__init__(defs)
        change = self.change

        class Reader(codec._Reader):
            def field(self, f, path):
                return change(f, super().field(f, path))
        self.Reader = Reader

    def change(self, f, value):
        return value


class CrcOverPayloadOnly(Stepwise):
    """The CRC covers the payload only, not the header (encoder and decoder alike)."""

    name = "crc-over-payload-only"

    def check_crc(self, frame, end, e):
        stored, computed = frame[end:end + FOOTER_SIZE], struct.pack(e + "H", cached_crc16(frame[HEADER_SIZE:end]))
        if stored != computed:
            raise FrameError("crc", end, f"stored CRC {stored.hex()}, computed {computed.hex()}")

    def encode_frame(self, message, byte_order):
        body = super().encode_frame(message, byte_order)[:-FOOTER_SIZE]
        return body + struct.pack(ORDERS[byte_order] + "H", crc16(body[HEADER_SIZE:]))


class CrcCcitt(Stepwise):
    """The footer is CRC-16/CCITT-FALSE (polynomial 0x1021, initial 0xFFFF) instead of CRC-16/ARC."""

    name = "crc-ccitt"

    @staticmethod
    @functools.cache
    def crc(body: bytes) -> int:
        value = 0xFFFF
        for byte in body:
            value ^= byte << 8
            for _ in range(8):
                value = ((value << 1) ^ 0x1021 if value & 0x8000 else value << 1) & 0xFFFF
        return value

    def encode_frame(self, message, byte_order):
        return with_footer(super().encode_frame(message, byte_order)[:-FOOTER_SIZE], ORDERS[byte_order], self.crc)


class CrcAlwaysBigEndian(Stepwise):
    """The CRC is written and read big-endian whatever the frame's byte order."""

    name = "crc-always-be"

    def crc_order(self, e):
        return ">"

    def encode_frame(self, message, byte_order):
        return with_footer(super().encode_frame(message, byte_order)[:-FOOTER_SIZE], ">")


class SizeCountsMore(Stepwise):
    """Base of the codecs whose size field counts ``extra`` bytes beyond the payload (written so, and read back so)."""

    extra = 0

    def payload_end(self, frame, size):
        return super().payload_end(frame, max(0, size - self.extra))

    def encode_frame(self, message, byte_order):
        e = ORDERS[byte_order]
        body = bytearray(super().encode_frame(message, byte_order)[:-FOOTER_SIZE])
        struct.pack_into(e + "H", body, 4, (len(body) - HEADER_SIZE + self.extra) & 0xFFFF)
        return with_footer(bytes(body), e)


class SizeCountsHeader(SizeCountsMore):
    """The size field counts the 20 header bytes too (written so, and read back so)."""

    name = "size-counts-header"
    extra = HEADER_SIZE


class SizeCountsFooter(SizeCountsMore):
    """The size field counts the two footer bytes too (written so, and read back so)."""

    name = "size-counts-footer"
    extra = FOOTER_SIZE


class ListCountU8(Stepwise):
    """A message-list's count is one byte, not two (encoder and decoder alike)."""

    name = "list-count-u8"

    class Reader(codec._Reader):
        def field(self, f, path):
            if f.type != "message-list":
                return super().field(f, path)
            start = self._take(1, "field-overrun", f"{path} count")
            return [self.inline(f"{path}[{i}]", "list-count-overrun") for i in range(self.frame[start])]

    def encode_frame(self, message, byte_order):
        frame = super().encode_frame(message, byte_order)
        e = ORDERS[byte_order]
        counts = [s for s in codec.layout(self.defs, frame) if s.role == "count"]
        body = bytearray(frame[:-FOOTER_SIZE])
        for s in reversed(counts):  # from the end, so earlier offsets stay true
            (n,) = struct.unpack_from(e + "H", body, s.start)
            body[s.start:s.end] = bytes([n & 0xFF])
        struct.pack_into(e + "H", body, 4, len(body) - HEADER_SIZE)
        return with_footer(bytes(body), e)


class NullInlineAsZero(Reference):
    """The encoder writes a null inline message as id 0x0000 instead of 0xFFFF."""

    name = "null-inline-as-zero"

    def encode_frame(self, message, byte_order):
        frame = super().encode_frame(message, byte_order)
        return rewrite_prefixes(self.defs, frame, byte_order,
                                lambda s, types: s.role == "id" and self._null_at(frame, byte_order, s),
                                lambda n: 0)

    def _null_at(self, frame, byte_order, span) -> bool:
        return struct.unpack_from(ORDERS[byte_order] + "H", frame, span.start)[0] == self.defs.null_id


class SyncFirstByteOnly(Stepwise):
    """Only the first sync byte is checked: 54 means little-endian and FE big-endian, whatever follows."""

    name = "sync-first-byte-only"

    def check_sync(self, frame):
        order = {0x54: "<", 0xFE: ">"}.get(frame[0])
        if order is None:
            raise FrameError("sync", 0, f"synchronization byte {frame[0]:02x}")
        return order


class RejectsBigEndian(Stepwise):
    """Big-endian frames are refused on decode (as if FE 54 were not a sync number)."""

    name = "rejects-big-endian"

    def check_sync(self, frame):
        if frame[:2] != b"\x54\xfe":
            raise FrameError("sync", 0, f"synchronization bytes {frame[:2].hex()}")
        return "<"


class SizeLimitOffByOne(Stepwise):
    """DUNE's frame cap held one byte short: a payload of 65,513 bytes (a 65,535-byte frame, which DUNE takes too) is
    refused."""

    name = "size-limit-off-by-one"

    def check_size(self, size):
        if size >= self.defs.max_payload:
            raise FrameError("size-limit", 4, f"size {size} reaches {self.defs.max_payload}")


class TimestampLittleEndianAlways(Stepwise):
    """The header timestamp is written and read little-endian whatever the frame's byte order."""

    name = "timestamp-always-le"

    def header(self, frame, e):
        (bits,) = struct.unpack_from("<Q", frame, 6)
        return dict(super().header(frame, e), timestamp=float_from_bits(bits, 8))

    def encode_frame(self, message, byte_order):
        frame = bytearray(super().encode_frame(message, byte_order)[:-FOOTER_SIZE])
        if byte_order == "be":
            frame[6:14] = frame[6:14][::-1]
        return with_footer(bytes(frame), ORDERS[byte_order])


class EntitiesSwapped(Stepwise):
    """src_ent and dst_ent trade places in the header (encoder and decoder alike)."""

    name = "entities-swapped"

    def header(self, frame, e):
        h = super().header(frame, e)
        return dict(h, src_ent=h["dst_ent"], dst_ent=h["src_ent"])

    def encode_frame(self, message, byte_order):
        frame = bytearray(super().encode_frame(message, byte_order)[:-FOOTER_SIZE])
        frame[16], frame[19] = frame[19], frame[16]
        return with_footer(bytes(frame), ORDERS[byte_order])


class DstIgnoredOnEncode(Reference):
    """The encoder always writes dst 0xFFFF (broadcast), whatever the message's header says."""

    name = "dst-ignored-on-encode"

    def encode_frame(self, message, byte_order):
        header = dict(message.get("header", {}), dst=0xFFFF)
        return super().encode_frame(dict(message, header=header), byte_order)


class Fp32AsFp64(Reference):
    """Generated from a wrong type map: every fp32 field is encoded and decoded as fp64."""

    name = "fp32-as-fp64"

    def __init__(self, defs):
        super().__init__(retype(defs, lambda m, f: f.type == "fp32_t", "fp64_t"))


class Int16AsUint16(Reference):
    """Generated from a wrong type map: every int16 field is read and written as uint16 (negatives refused)."""

    name = "int16-as-uint16"

    def __init__(self, defs):
        super().__init__(retype(defs, lambda m, f: f.type == "int16_t", "uint16_t"))


class Uint32ReadSigned(ValueMutant):
    """uint32 fields are decoded as int32: values from 2^31 come out negative."""

    name = "uint32-read-signed"

    def change(self, f, value):
        return value - (1 << 32) if f.type == "uint32_t" and value >= 1 << 31 else value


class Int16MinSaturates(ValueMutant):
    """An int16 of -32768 decodes as -32767 (a symmetric-range clamp applied on read)."""

    name = "int16-min-saturates"

    def change(self, f, value):
        return -32767 if f.type == "int16_t" and value == -32768 else value


class Uint8Saturates(ValueMutant):
    """uint8 values above 200 decode as 200 (a clamp meant for a percentage, applied to every uint8)."""

    name = "uint8-saturates-200"

    def change(self, f, value):
        return min(value, 200) if f.type == "uint8_t" and f.enum_kind is None else value


class Fp64ConditionalBug(ValueMutant):
    """An fp64 field between 1e3 and 1e5 in magnitude decodes one unit in the last place off (a fast-path
    conversion bug): every other value is right."""

    name = "fp64-wrong-1e3-1e5"

    def change(self, f, value):
        if f.type == "fp64_t" and isinstance(value, float) and 1e3 < abs(value) < 1e5:
            return math.nextafter(value, math.inf)
        return value


class DropsFifthListElement(ValueMutant):
    """A message-list of exactly five elements decodes without its last one."""

    name = "drops-fifth-list-element"

    def change(self, f, value):
        return value[:4] if f.type == "message-list" and len(value) == 5 else value


class TrimsTrailingSpaces(ValueMutant):
    """Plaintext loses its trailing spaces on decode."""

    name = "trims-trailing-spaces"

    def change(self, f, value):
        return value.rstrip(" ") if f.type == "plaintext" and isinstance(value, str) else value


class RawdataLosesLastOddByte(ValueMutant):
    """Rawdata of an odd length loses its last byte on decode (a 16-bit copy loop)."""

    name = "rawdata-loses-odd-byte"

    def change(self, f, value):
        return value[:-2] if f.type == "rawdata" and len(value) % 4 == 2 else value


class BitfieldDropsTopBit(ValueMutant):
    """A bitfield loses the top bit of its field's width on decode."""

    name = "bitfield-drops-top-bit"

    def change(self, f, value):
        return value & ~(1 << (8 * f.size - 1)) if f.enum_kind == "bitfield" else value


class LastEnumValueOffByOne(ValueMutant):
    """The last value of each enumeration table decodes as the value before it."""

    name = "last-enum-value-off-by-one"

    def change(self, f, value):
        if f.enum_kind == "enum" and f.enum_values and value == f.enum_values[-1].value:
            return value - 1
        return value


class NestedInlineIsNull(Stepwise):
    """An inline message inside an inline message decodes as null (only one level is followed)."""

    name = "nested-inline-is-null"

    class Reader(codec._Reader):
        def inline(self, path, rule):
            value = super().inline(path, rule)
            return None if self.depth >= 1 and value is not None else value


class EmptyListAsNullCount(Reference):
    """The encoder writes an empty message-list's count as 0xFFFF (a null marker) instead of 0."""

    name = "empty-list-as-null-count"

    def encode_frame(self, message, byte_order):
        frame = super().encode_frame(message, byte_order)
        return rewrite_prefixes(self.defs, frame, byte_order, lambda s, types: s.role == "count"
                                and struct.unpack_from(ORDERS[byte_order] + "H", frame, s.start)[0] == 0,
                                lambda n: 0xFFFF)


class PlaintextCutAt255(Reference):
    """The encoder keeps at most 255 bytes of a plaintext (a u8 length habit), writing the shortened length."""

    name = "plaintext-cut-at-255"

    def encode_frame(self, message, byte_order):
        return super().encode_frame(_cut_texts(self.defs, message), byte_order)


class NanCanonicalOnEncode(Reference):
    """The encoder writes every NaN as the default quiet NaN (its payload and sign lost)."""

    name = "nan-canonical-on-encode"

    def encode_frame(self, message, byte_order):
        return super().encode_frame(_map_floats(message, lambda v: "nan" if isinstance(v, str) and v.startswith("nan")
                                                else v), byte_order)


class NegativeZeroTimestampLost(Stepwise):
    """A header timestamp of -0.0 decodes as 0.0."""

    name = "negative-zero-timestamp-lost"

    def header(self, frame, e):
        h = super().header(frame, e)
        return dict(h, timestamp=0.0) if h["timestamp"] == 0 else h


class Int8MinAsPositive(ValueMutant):
    """An int8 of -128 decodes as 128 (a sign-extension slip for the one value without a positive twin)."""

    name = "int8-min-as-positive"

    def change(self, f, value):
        return 128 if f.type == "int8_t" and value == -128 else value


class ListElementsReversed(ValueMutant):
    """The elements of a message-list come out in reverse order (built by prepending)."""

    name = "list-elements-reversed"

    def change(self, f, value):
        return value[::-1] if f.type == "message-list" else value


def _cut_texts(defs, message):
    """``message`` with every plaintext (nested ones included) cut to 255 bytes."""
    mdef = defs.by_abbrev.get(message.get("abbrev")) if isinstance(message, dict) else None
    if mdef is None or not isinstance(message.get("fields"), dict):
        return message
    fields = dict(message["fields"])
    for f in mdef.fields:
        v = fields.get(f.abbrev)
        if f.type == "plaintext" and v is not None:
            fields[f.abbrev] = text_value(text_bytes(v)[:255])
        elif f.type == "message" and isinstance(v, dict):
            fields[f.abbrev] = _cut_texts(defs, v)
        elif f.type == "message-list" and isinstance(v, list):
            fields[f.abbrev] = [_cut_texts(defs, x) if isinstance(x, dict) else x for x in v]
    return dict(message, fields=fields)


def _map_floats(value, change):
    """``value`` with ``change`` applied to every float-valued leaf (numbers and NaN/infinity strings) of its fields."""
    if isinstance(value, dict):
        return {k: (v if k in ("abbrev", "header") else _map_floats(v, change)) for k, v in value.items()}
    if isinstance(value, list):
        return [_map_floats(v, change) for v in value]
    if isinstance(value, float) or isinstance(value, str) and value.startswith(("nan", "inf", "-inf")):
        return change(value)
    return value
