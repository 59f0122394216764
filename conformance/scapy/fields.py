"""Scapy fields for IMC values: numbers, enums, bitfields and floats in the current byte order, and byte
strings after a u16 length.

Besides scapy's conversions, each field converts its internal value to the corpus's decoded form (``i2d``)
and back (``d2i``).
"""

from __future__ import annotations

import struct

from scapy.fields import EnumField, Field, FlagsField, StrField

from ..kinds.vector.floats import float_from_bits, float_to_bits
from ..suites.imc.values import raw_bytes, text_bytes, text_value
from .byteorder import prefix


def with_unit(text: str, unit: str | None) -> str:
    return f"{text} {unit}" if unit else text


class Ordered:
    """Mixin: a value of the struct code ``code``, packed in the current byte order."""

    code: str

    def addfield(self, pkt, s: bytes, val) -> bytes:
        return s + struct.pack(prefix() + self.code, self.i2m(pkt, val))

    def getfield(self, pkt, s: bytes):
        size = struct.calcsize(self.code)
        (value,) = struct.unpack(prefix() + self.code, s[:size])  # struct.error when s is short
        return s[size:], self.m2i(pkt, value)

    def i2d(self, x) -> int:
        return int(x)

    def d2i(self, value):
        return value


class Number(Ordered, Field):
    """An integer, shown with its unit."""

    def __init__(self, name: str, default, code: str, unit: str | None = None):
        self.code, self.unit = code, unit
        Field.__init__(self, name, default, code)

    def i2repr(self, pkt, x) -> str:
        return with_unit(super().i2repr(pkt, x), self.unit if x is not None else None)


class Checksum(Number):
    """An integer shown in hexadecimal."""

    def i2repr(self, pkt, x) -> str:
        return "None" if x is None else f"0x{x:04x}"


class Enum(Ordered, EnumField):
    """An integer shown by the name of its value; names are accepted on assignment."""

    def __init__(self, name: str, default, code: str, names: dict[int, str]):
        self.code = code
        EnumField.__init__(self, name, default, names, code)


class Flags(Ordered, FlagsField):
    """A bitfield shown as its flags' names (``EXTERNAL+LOCAL``)."""

    def __init__(self, name: str, default, code: str, names: dict[int, str]):
        self.code = code
        FlagsField.__init__(self, name, default, 8 * struct.calcsize(code), names)

    def i2m(self, pkt, x) -> int:
        return int(super().i2m(pkt, x))


class Float(Ordered, Field):
    """An IEEE float of ``width`` bytes, packed by its bits. Its value is a Python float, or the decoded
    form's string (``"nan:7f800001"``) for a NaN whose bits a Python float does not keep; the decoded
    form's strings are accepted on assignment."""

    def __init__(self, name: str, default, width: int, unit: str | None = None):
        self.code, self.width, self.unit = {4: "I", 8: "Q"}[width], width, unit
        Field.__init__(self, name, default, self.code)

    def m2i(self, pkt, bits: int):
        (x,) = struct.unpack("<" + {4: "f", 8: "d"}[self.width], struct.pack("<" + self.code, bits))
        return x if float_to_bits(x, self.width) == bits else float_from_bits(bits, self.width)

    def i2m(self, pkt, x) -> int:
        return float_to_bits(0.0 if x is None else x, self.width)

    def any2i(self, pkt, x):
        return self.m2i(pkt, float_to_bits(x, self.width)) if isinstance(x, str) else x

    def i2repr(self, pkt, x) -> str:
        return "None" if x is None else with_unit(str(self.i2d(x)), self.unit)

    def i2d(self, x):
        """The shortest decimal that keeps the bits, or the string of a NaN or an infinity."""
        return float_from_bits(float_to_bits(x, self.width), self.width)

    def d2i(self, value):
        return self.any2i(None, value)


class LengthPrefixed(StrField):
    """Bytes after their u16 length."""

    def __init__(self, name: str):
        StrField.__init__(self, name, b"")

    def addfield(self, pkt, s: bytes, val) -> bytes:
        data = self.i2m(pkt, val)
        return s + struct.pack(prefix() + "H", len(data)) + data

    def getfield(self, pkt, s: bytes):
        (length,) = struct.unpack(prefix() + "H", s[:2])
        if len(s) < 2 + length:
            raise ValueError(f"{self.name}: {length} bytes announced, {len(s) - 2} left")
        return s[2 + length:], s[2:2 + length]


class Text(LengthPrefixed):
    """An IMC plaintext."""

    def i2d(self, x):
        return text_value(x)

    def d2i(self, value) -> bytes:
        return text_bytes(value)


class Data(LengthPrefixed):
    """An IMC rawdata."""

    def i2d(self, x) -> str:
        return x.hex()

    def d2i(self, value) -> bytes:
        return raw_bytes(value)
