"""Mutant IMC implementations: the reference codec with one seeded bug each.

"A suite that never fails proves nothing": tests/test_mutants.py runs every mutant over the corpus and
shows which cases catch its bug. ``Reference`` wraps the reference codec as a library adapter;
``Stepwise`` rebuilds its decoder from the codec's pieces, one method per check in DUNE's order, so
that a mutant overrides exactly the check or the reading it gets wrong. Each mutant's docstring is
its bug.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import struct

from . import codec
from ...adapter_api import Rejected, Unsupported
from .codec import FOOTER_SIZE, HEADER_SIZE, ORDERS, EncodeError, FrameError
from .crc16 import crc16
from .definitions import MessageDef
from ...kinds.vector.floats import float_from_bits
from .values import text_bytes, text_value

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


# ---------------------------------------------------------------- one mutant per rule of rules.json

class RuleOff(Reference):
    """The reference codec with one rule switched off (``off``): what a reader or writer without that check does is
    the codec's own ``LENIENT`` behaviour, the one the oracle proves the corpus against."""

    off: str

    def decode_frame(self, frame: bytes) -> dict:
        return codec.decode(self.defs, frame, off=frozenset((self.off,)))

    def encode_frame(self, message: dict, byte_order: str) -> bytes:
        return codec.encode(self.defs, message, byte_order, off=frozenset((self.off,)))


def rule_off(rule: str, equivalent: str | None = None) -> type:
    """The mutant that does not check ``rule`` (named ``<rule>-unchecked``; its bug is the codec's LENIENT text)."""
    attributes = {"name": f"{rule}-unchecked", "off": rule, "__doc__": f"{rule}: {codec.LENIENT[rule]}."}
    if equivalent:
        attributes["equivalent"] = equivalent
    return type(class_name(rule), (RuleOff,), attributes)


def class_name(rule: str) -> str:
    """``crc`` -> ``CrcUnchecked``: the mutant's name in this module (``imc_conformance.suites.imc.mutants``)."""
    return "".join(part.capitalize() for part in rule.split("-")) + "Unchecked"


HeaderTruncatedUnchecked = rule_off(
    "header-truncated", "a frame shorter than the header has no room for its payload and CRC: padded, it still breaks "
                        "size-exceeds-data, so a reader without this check refuses every such frame (the oracle's "
                        "flaws of every header-truncated case)")
SyncUnchecked = rule_off("sync")
SizeExceedsDataUnchecked = rule_off("size-exceeds-data")
CrcUnchecked = rule_off("crc")
UnknownIdUnchecked = rule_off("unknown-id")
FieldOverrunUnchecked = rule_off("field-overrun")
LengthOverrunUnchecked = rule_off("length-overrun")
ListCountOverrunUnchecked = rule_off("list-count-overrun")
UnknownInlineIdUnchecked = rule_off("unknown-inline-id")
PayloadOverflowUnchecked = rule_off("payload-overflow")
PER_RULE = (HeaderTruncatedUnchecked, SyncUnchecked, SizeExceedsDataUnchecked, CrcUnchecked, UnknownIdUnchecked,
            FieldOverrunUnchecked, LengthOverrunUnchecked, ListCountOverrunUnchecked, UnknownInlineIdUnchecked,
            PayloadOverflowUnchecked)


# ---------------------------------------------------------------- the right refusal, the wrong rule

class BlamesCrc(Reference):
    """Wrong rule: every refusal is right, but always reported as rule "crc"."""

    name = "blames-crc"

    def encode(self, suite, message, byte_order):
        try:
            return super().encode(suite, message, byte_order)
        except Rejected as exc:
            raise Rejected(exc.reason, rule="crc") from exc

    def decode(self, suite, frame):
        try:
            return super().decode(suite, frame)
        except Rejected as exc:
            raise Rejected(exc.reason, rule="crc") from exc


# ---------------------------------------------------------------- encoding and value bugs

class CrcLittleEndianInBe(Stepwise):
    """The CRC of a big-endian frame is written and read little-endian."""

    name = "crc-le-in-be"

    def crc_order(self, e: str) -> str:
        return "<"

    def encode_frame(self, message, byte_order):
        return with_footer(super().encode_frame(message, byte_order)[:-FOOTER_SIZE], "<")


class CrcModbus(Stepwise):
    """The footer is CRC-16/MODBUS (initial value 0xFFFF) instead of CRC-16/ARC (initial value 0)."""

    name = "crc-modbus"

    def crc(self, body: bytes) -> int:
        return cached_crc16(body, 0xFFFF)

    def encode_frame(self, message, byte_order):
        return with_footer(super().encode_frame(message, byte_order)[:-FOOTER_SIZE], ORDERS[byte_order], self.crc)


class BePayloadLittleEndian(Stepwise):
    """Big-endian frames get a big-endian header but a little-endian payload (encoder and decoder alike)."""

    name = "be-payload-le"

    def payload_order(self, e: str) -> str:
        return "<"

    def encode_frame(self, message, byte_order):
        frame = super().encode_frame(message, byte_order)
        if byte_order == "le":
            return frame
        payload = codec.encode_payload(self.defs, self.defs[message["abbrev"]], message["fields"], "<")
        return with_footer(frame[:HEADER_SIZE] + payload, ">")


class FloatMutant(Stepwise):
    """Base of the decoders that alter float field values through ``value``."""

    class Reader(codec._Reader):
        def field(self, f, path):
            value = super().field(f, path)
            return self.value(value, f.size) if f.is_float else value


class DropsNegativeZero(FloatMutant):
    """-0.0 in a float field decodes as 0.0 (the header timestamp is unaffected)."""

    name = "drops-negative-zero"

    class Reader(FloatMutant.Reader):
        @staticmethod
        def value(x, width):
            return 0.0 if x == 0 else x


class FlushesSubnormals(FloatMutant):
    """Subnormal floats in fields decode as zero of the same sign (flush-to-zero)."""

    name = "flushes-subnormals"

    class Reader(FloatMutant.Reader):
        @staticmethod
        def value(x, width):
            if isinstance(x, float) and 0 < abs(x) < MIN_NORMAL[width]:
                return math.copysign(0.0, x)
            return x


class CanonicalNan(FloatMutant):
    """Every NaN in a float field decodes as the default quiet NaN (payload and sign lost)."""

    name = "canonical-nan"

    class Reader(FloatMutant.Reader):
        @staticmethod
        def value(x, width):
            return "nan" if isinstance(x, str) and x.startswith("nan") else x


class PlaintextStopsAtNul(Stepwise):
    """Plaintext is decoded as a C string: it ends at the first NUL byte."""

    name = "plaintext-stops-at-nul"

    class Reader(codec._Reader):
        def field(self, f, path):
            value = super().field(f, path)
            return text_value(text_bytes(value).split(b"\0")[0]) if f.type == "plaintext" else value


class PlaintextLengthPlusOne(Reference):
    """The encoder writes a plaintext's length prefix one too large (it counts a terminating NUL it does not send)."""

    name = "plaintext-length-plus-one"

    def encode_frame(self, message, byte_order):
        frame = super().encode_frame(message, byte_order)
        return rewrite_prefixes(self.defs, frame, byte_order,
                                lambda s, types: s.role == "length" and types[s.path[:-len(".length")]] == "plaintext",
                                lambda n: n + 1)


class ListCountMinusOne(Reference):
    """The encoder writes a message-list's count as its number of elements minus one."""

    name = "list-count-minus-one"

    def encode_frame(self, message, byte_order):
        frame = super().encode_frame(message, byte_order)
        return rewrite_prefixes(self.defs, frame, byte_order, lambda s, types: s.role == "count", lambda n: n - 1)


class RssiValueAsFp64(Reference):
    """Generated from a wrong definition: RSSI.value (fp32) is encoded and decoded as fp64."""

    name = "rssi-value-as-fp64"

    def __init__(self, defs):
        super().__init__(retype(defs, lambda m, f: m.abbrev == "RSSI" and f.abbrev == "value", "fp64_t"))


class SignedSrc(Stepwise):
    """The header's src (uint16) is decoded as a signed int16."""

    name = "signed-src"

    def header(self, frame, e):
        (src,) = struct.unpack_from(e + "h", frame, 14)
        return dict(super().header(frame, e), src=src)


class IgnoresTimestamp(Stepwise):
    """The header timestamp is not read: every decoded message has the default -1.0."""

    name = "ignores-timestamp"

    def header(self, frame, e):
        return dict(super().header(frame, e), timestamp=-1.0)


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


# ---------------------------------------------------------------- readers nobody here wrote (issue: verdicts for unseen code)

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


# ---------------------------------------------------------------- permitted choices: these must survive

class RefusesTrailingBytes(Stepwise):
    """Refuses a frame with bytes after the footer (imc-wire permits it: an acceptable case, not a failure)."""

    name = "refuses-trailing-bytes"
    equivalent = "imc-wire permits refusing bytes after the footer (acceptable cases): a conforming choice"

    def payload_end(self, frame, size):
        end = super().payload_end(frame, size)
        if len(frame) > end + FOOTER_SIZE:
            raise Rejected(f"{len(frame) - end - FOOTER_SIZE} bytes after the footer")
        return end


class LittleEndianOnly(Reference):
    """Emits only little-endian frames and says so (byte_orders ["le"]); it still decodes both orders."""

    name = "le-only"
    byte_orders = ("le",)
    equivalent = "an implementation may emit one byte order and say so in its hello: a conforming choice"

    def encode_frame(self, message, byte_order):
        if byte_order != "le":
            raise Unsupported(f"{byte_order!r} frames are not emitted")
        return super().encode_frame(message, byte_order)


MUTANTS = (
    *PER_RULE, BlamesCrc,
    CrcLittleEndianInBe, CrcModbus, BePayloadLittleEndian, DropsNegativeZero, FlushesSubnormals, CanonicalNan,
    PlaintextStopsAtNul, PlaintextLengthPlusOne, ListCountMinusOne, RssiValueAsFp64, SignedSrc, IgnoresTimestamp,
    RefusesTrailingBytes, LittleEndianOnly,
    CrcOverPayloadOnly, CrcCcitt, CrcAlwaysBigEndian, SizeCountsHeader, SizeCountsFooter, ListCountU8, NullInlineAsZero,
    SyncFirstByteOnly, RejectsBigEndian, SizeLimitOffByOne, TimestampLittleEndianAlways, EntitiesSwapped,
    DstIgnoredOnEncode, Fp32AsFp64, Int16AsUint16, Uint32ReadSigned, Int16MinSaturates, Uint8Saturates, Fp64ConditionalBug,
    DropsFifthListElement, TrimsTrailingSpaces, RawdataLosesLastOddByte, BitfieldDropsTopBit, LastEnumValueOffByOne,
    NestedInlineIsNull, EmptyListAsNullCount, PlaintextCutAt255, NanCanonicalOnEncode, NegativeZeroTimestampLost,
    Int8MinAsPositive, ListElementsReversed,
    IgnoresSize, CrcAtEndOfData, RestampsTimestamps, RestampsZeroTimestamps, CrashesOnNullElement, HoldsSizeLimit,
)
NEW = MUTANTS[MUTANTS.index(CrcOverPayloadOnly):MUTANTS.index(IgnoresSize)]  # added with the fuzzer
UNSEEN = MUTANTS[MUTANTS.index(IgnoresSize):]  # readers nobody here wrote: each caught by the corpus itself
