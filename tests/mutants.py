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

from imc_conformance.suites.imc import codec
from imc_conformance.adapter_api import Rejected, Unsupported
from imc_conformance.suites.imc.codec import FOOTER_SIZE, HEADER_SIZE, ORDERS, EncodeError, FrameError
from imc_conformance.suites.imc.crc16 import crc16
from imc_conformance.suites.imc.definitions import MessageDef
from imc_conformance.kinds.vector.floats import float_from_bits
from imc_conformance.suites.imc.values import text_bytes, text_value

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
        if size > self.defs.max_payload:
            raise FrameError("size-limit", 4, f"size {size} exceeds {self.defs.max_payload}")

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

class PadsShortHeader(Stepwise):
    """header-truncated: a frame shorter than the 20-byte header is zero-padded to one instead of rejected."""

    name = "pads-short-header"

    def check_length(self, frame: bytes) -> bytes:
        return frame.ljust(HEADER_SIZE, b"\0")


class AnySyncIsLittleEndian(Stepwise):
    """sync: no synchronization check; any first two bytes but FE 54 mean a little-endian frame."""

    name = "any-sync-is-le"

    def check_sync(self, frame: bytes) -> str:
        return ">" if codec.byte_order_of(frame) == "be" else "<"


class NoSizeLimit(Reference):
    """size-limit: the payload limit is the u16 maximum 65535, not 65513, in the decoder and the encoder."""

    name = "no-size-limit"

    def __init__(self, defs):
        super().__init__(dataclasses.replace(defs, max_payload=0xFFFF))


class ReadsWhatIsThere(Stepwise):
    """size-exceeds-data: no check that size + 22 bytes are present; a short frame's payload is what lies
    between the header and its last two bytes, which are taken as the CRC."""

    name = "reads-what-is-there"

    def payload_end(self, frame: bytes, size: int) -> int:
        return min(HEADER_SIZE + size, max(HEADER_SIZE, len(frame) - FOOTER_SIZE))


class NoCrcCheck(Stepwise):
    """crc: the footer is never compared with the CRC of the frame."""

    name = "no-crc-check"

    def check_crc(self, frame: bytes, end: int, e: str) -> None:
        pass


class UnknownIdIsEmpty(Stepwise):
    """unknown-id: an undefined or null message id decodes as a message without fields."""

    name = "unknown-id-is-empty"

    def message_def(self, mgid: int) -> MessageDef:
        return self.defs.by_id.get(mgid) or MessageDef(id=mgid, abbrev=f"Unknown{mgid}", name="Unknown", clause="",
                                                         fields=(), min_payload=0)


class PadsShortPayload(Stepwise):
    """field-overrun: a scalar, length/count prefix or inline id past the payload end reads zero bytes."""

    name = "pads-short-payload"

    class Reader(codec._Reader):
        def _take(self, count, rule, what):
            missing = self.pos + count - self.end
            if rule == "field-overrun" and missing > 0:
                self.frame, self.end = self.frame[:self.end] + bytes(missing), self.end + missing
            return super()._take(count, rule, what)


class ClampsLengths(Stepwise):
    """length-overrun: a plaintext or rawdata length past the payload end is clamped to the bytes left."""

    name = "clamps-lengths"

    class Reader(codec._Reader):
        def _take(self, count, rule, what):
            if rule == "length-overrun":
                count = min(count, self.end - self.pos)
            return super()._take(count, rule, what)


class ListStopsAtPayloadEnd(Stepwise):
    """list-count-overrun: a message-list ends at the payload end, whatever its count claims."""

    name = "list-stops-at-payload-end"

    class Reader(codec._Reader):
        def field(self, f, path):
            if f.type != "message-list":
                return super().field(f, path)
            count = self._u16("field-overrun", f"{path} count", path + ".count", "count")
            elements = []
            for i in range(count):
                if self.pos == self.end:
                    break
                elements.append(self.inline(f"{path}[{i}]", "list-count-overrun"))
            return elements


class UnknownInlineIdIsNull(Stepwise):
    """unknown-inline-id: an inline message or list element with an undefined id decodes as null."""

    name = "unknown-inline-id-is-null"

    class Reader(codec._Reader):
        def inline(self, path, rule):
            start = self.pos
            mgid = self._u16(rule, f"{path} message id", path + ".id", "id")
            if mgid not in self.defs.by_id:
                return None
            self.pos = start
            return super().inline(path, rule)


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
        rssi = defs["RSSI"]
        wide = dataclasses.replace(rssi, fields=tuple(dataclasses.replace(f, type="fp64_t") for f in rssi.fields))
        super().__init__(dataclasses.replace(defs, messages=tuple(wide if m is rssi else m for m in defs.messages)))


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


# ---------------------------------------------------------------- permitted choices: these must survive

class RefusesTrailingBytes(Stepwise):
    """Refuses a frame with bytes after the footer (imc-wire permits it: an acceptable case, not a failure)."""

    name = "refuses-trailing-bytes"

    def payload_end(self, frame, size):
        end = super().payload_end(frame, size)
        if len(frame) > end + FOOTER_SIZE:
            raise Rejected(f"{len(frame) - end - FOOTER_SIZE} bytes after the footer")
        return end


class LittleEndianOnly(Reference):
    """Emits only little-endian frames and says so (byte_orders ["le"]); it still decodes both orders."""

    name = "le-only"
    byte_orders = ("le",)

    def encode_frame(self, message, byte_order):
        if byte_order != "le":
            raise Unsupported(f"{byte_order!r} frames are not emitted")
        return super().encode_frame(message, byte_order)


MUTANTS = (
    PadsShortHeader, AnySyncIsLittleEndian, NoSizeLimit, ReadsWhatIsThere, NoCrcCheck, UnknownIdIsEmpty,
    PadsShortPayload, ClampsLengths, ListStopsAtPayloadEnd, UnknownInlineIdIsNull, BlamesCrc,
    CrcLittleEndianInBe, CrcModbus, BePayloadLittleEndian, DropsNegativeZero, FlushesSubnormals, CanonicalNan,
    PlaintextStopsAtNul, PlaintextLengthPlusOne, ListCountMinusOne, RssiValueAsFp64, SignedSrc, IgnoresTimestamp,
    RefusesTrailingBytes, LittleEndianOnly,
)
