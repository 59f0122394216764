"""Seeded encoding and value bugs: the first set, each caught by the corpus."""

from __future__ import annotations

import math
import struct

from .. import codec
from ..codec import FOOTER_SIZE, HEADER_SIZE, ORDERS
from ..values import text_bytes, text_value
from .base import MIN_NORMAL, Reference, Stepwise, cached_crc16, retype, rewrite_prefixes, with_footer


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
