"""Sans-IO reference codec for ROS 1 serialization, generic over the definitions of one edition.

ROS 1 is little-endian and packed: bool and 8-bit integers take one byte, then 2, 4 and 8 bytes;
``time`` is uint32 secs + uint32 nsecs, ``duration`` int32 + int32; a ``string`` is a uint32 byte count
and the bytes; ``T[]`` a uint32 element count and the elements, ``T[N]`` exactly N elements; nested
messages are inlined field by field. Nothing names the type on the wire: decoding needs it.

The decoded form: ``{"type": "ros_acomms_msgs/CST", "fields": {...}}``; a nested message is the object of
its fields; ``bool`` a JSON boolean; integers JSON integers (64-bit ones beyond 2**53 as decimal strings;
either form is accepted); floats as in every suite (``kinds.vector.floats``); ``time`` and ``duration``
``{"secs", "nsecs"}``; a string a JSON string when its bytes are UTF-8, else ``{"hex": ...}``; ``uint8[]``
and ``uint8[N]`` lowercase hex; other arrays JSON arrays. ``decode`` raises ``FrameError`` naming the
broken rule (``truncated``, ``length-overrun``) and the byte offset; bytes after the message are ignored
(as genpy, the canonical ROS 1 Python code, does; whether to accept them is implementation-defined).

Each decoding rule has a switch (``off``): a rule switched off is replaced by what a reader without that check does
(``LENIENT``), which is how ``generate --check`` proves that an invalid vector breaks exactly the rules it names.
"""

from __future__ import annotations

import struct

from ...kinds.vector import Span
from ...kinds.vector.errors import EncodeError, FrameError
from ...kinds.vector.floats import float_from_bits, float_to_bits
from .definitions import PRIMITIVES, Edition, FieldType, Message

EXACT_JSON = 2 ** 53  # integers at least this large are written as decimal strings
LENIENT = {
    "truncated": "the bytes a field needs past the end read as zeros",
    "length-overrun": "a length or count is clamped to what the bytes left can hold",
}
NONE: frozenset[str] = frozenset()
TIME = {"time": "<II", "duration": "<ii"}


def int_bounds(base: str) -> tuple[int, int]:
    size = PRIMITIVES[base][1] * 8
    return (0, (1 << size) - 1) if base.startswith("u") else (-(1 << (size - 1)), (1 << (size - 1)) - 1)


def int_value(value) -> int | None:
    """The integer a decoded-form value stands for (a JSON integer or a decimal string), else None."""
    if type(value) is int:
        return value
    if isinstance(value, str) and value.lstrip("-").isdigit():
        return int(value)
    return None


def int_form(value: int):
    return value if abs(value) < EXACT_JSON else str(value)


def string_value(raw: bytes):
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError:
        return {"hex": raw.hex()}


def string_bytes(value) -> bytes:
    if isinstance(value, str):
        return value.encode("utf-8")
    if isinstance(value, dict) and set(value) == {"hex"} and isinstance(value["hex"], str):
        return bytes.fromhex(value["hex"])
    raise ValueError(f"{value!r} is not a string value")


def min_size(edition: Edition, ftype: FieldType) -> int:
    """The fewest bytes a value of this type takes (an empty string or array: its prefix)."""
    if ftype.array is not None:
        return 4 if ftype.array < 0 else ftype.array * min_size(edition, ftype.element)
    if ftype.base in PRIMITIVES:
        return PRIMITIVES[ftype.base][1]
    if ftype.base in ("string", "time", "duration"):
        return 4 if ftype.base == "string" else 8
    return sum(min_size(edition, f.type) for f in edition[ftype.base].fields)


# ---------------------------------------------------------------- encoding

def encode(edition: Edition, message: dict, encoding: str = "ros1") -> bytes:
    """The ROS 1 bytes of ``message`` (decoded form); raises EncodeError."""
    if encoding != "ros1":
        raise EncodeError("value-type", f"no encoding {encoding!r}")
    if not isinstance(message, dict):
        raise EncodeError("value-type", "a message must be an object")
    full = message.get("type")
    if not isinstance(full, str) or full not in edition:
        raise EncodeError("unknown-type", f"unknown type {str(full)[:80]!r}")
    out = bytearray()
    _fields(edition, edition[full], message.get("fields"), full, out)
    return bytes(out)


def _fields(edition: Edition, message: Message, fields, where: str, out: bytearray) -> None:
    if not isinstance(fields, dict):
        raise EncodeError("value-type", f"{where}: fields must be an object")
    unknown = sorted(set(fields) - {f.name for f in message.fields})
    if unknown:
        raise EncodeError("unknown-field", f"{message.full} has no field {unknown[0]!r}")
    for f in message.fields:
        if f.name not in fields:
            raise EncodeError("missing-field", f"{message.full}.{f.name} is missing")
        _value(edition, f.type, fields[f.name], f"{where}.{f.name}", out)


def _value(edition: Edition, ftype: FieldType, value, where: str, out: bytearray) -> None:
    try:
        if ftype.array is not None:
            _array(edition, ftype, value, where, out)
        elif ftype.base == "bool":
            if not isinstance(value, bool):
                raise EncodeError("value-type", f"{where}: {value!r} is not a boolean")
            out.append(1 if value else 0)
        elif ftype.base in ("float32", "float64"):
            size = PRIMITIVES[ftype.base][1]
            out += float_to_bits(value, size).to_bytes(size, "little")
        elif ftype.base in PRIMITIVES:
            number = int_value(value)
            if number is None:
                raise EncodeError("value-type", f"{where}: {value!r} is not an integer")
            lo, hi = int_bounds(ftype.base)
            if not lo <= number <= hi:
                raise EncodeError("value-out-of-type", f"{where}: {number} does not fit {ftype.base} [{lo}, {hi}]")
            out += struct.pack("<" + PRIMITIVES[ftype.base][0], number)
        elif ftype.base == "string":
            data = string_bytes(value)
            out += struct.pack("<I", len(data)) + data
        elif ftype.base in TIME:
            if not isinstance(value, dict) or set(value) != {"secs", "nsecs"}:
                raise EncodeError("value-type", f"{where}: {ftype.base} must be {{secs, nsecs}}")
            out += struct.pack(TIME[ftype.base], value["secs"], value["nsecs"])
        else:
            _fields(edition, edition[ftype.base], value, where, out)
    except EncodeError:
        raise
    except struct.error as exc:
        raise EncodeError("value-out-of-type", f"{where}: {exc}") from exc
    except (ValueError, TypeError) as exc:
        raise EncodeError("value-type", f"{where}: {exc}") from exc


def _array(edition: Edition, ftype: FieldType, value, where: str, out: bytearray) -> None:
    if ftype.base == "uint8":  # a byte blob, written as hex
        data = bytes.fromhex(value) if isinstance(value, str) else None
        if data is None:
            raise EncodeError("value-type", f"{where}: uint8 arrays are hex strings")
        count = len(data)
    elif isinstance(value, list):
        count = len(value)
    else:
        raise EncodeError("value-type", f"{where}: {ftype.text('')} must be an array")
    if ftype.array >= 0 and count != ftype.array:
        raise EncodeError("fixed-array-length", f"{where}: {count} elements for {ftype.text('')}")
    if ftype.array < 0:
        out += struct.pack("<I", count)
    if ftype.base == "uint8":
        out += data
        return
    for i, element in enumerate(value):
        _value(edition, ftype.element, element, f"{where}[{i}]", out)


# ---------------------------------------------------------------- decoding

def decode(edition: Edition, full: str, frame: bytes, spans: list[Span] | None = None, *,
           off: frozenset[str] = NONE) -> dict:
    """The decoded form of ``frame`` as type ``full``; raises FrameError. Appends the byte map to ``spans``. ``off``:
    the rules switched off (see the module's docstring)."""
    if full not in edition:
        raise FrameError("unknown-type", 0, f"unknown type {full!r}")
    reader = _Reader(edition, frame, spans, off)
    return {"type": full, "fields": reader.fields(edition[full], edition[full].name)}


def layout(edition: Edition, full: str, frame: bytes) -> list[Span]:
    """The byte map of a frame of type ``full`` (every field, length and count), in offset order."""
    spans: list[Span] = []
    decode(edition, full, frame, spans)
    return sorted(spans, key=lambda s: (s.start, s.end))


class _Reader:
    def __init__(self, edition: Edition, frame: bytes, spans: list[Span] | None, off: frozenset[str] = NONE):
        self.edition, self.frame, self.spans, self.off = edition, frame, spans, off
        self.pos = 0

    def take(self, count: int, what: str) -> int:
        start = self.pos
        if start + count > len(self.frame):
            if "truncated" not in self.off:
                raise FrameError("truncated", start, f"{what} needs {count} bytes, {len(self.frame) - start} left")
            self.frame += bytes(start + count - len(self.frame))
        self.pos += count
        return start

    def mark(self, start: int, path: str, type_: str, role: str = "value") -> None:
        if self.spans is not None:
            self.spans.append(Span(start, self.pos, path, type_, role))

    def fields(self, message: Message, path: str) -> dict:
        return {f.name: self.value(f.type, f"{path}.{f.name}") for f in message.fields}

    def count(self, path: str, ftype: FieldType) -> int:
        """A length or count prefix, checked against the bytes left (no allocation can follow a hostile one)."""
        start = self.take(4, f"{path} length")
        self.mark(start, f"{path}.length", "uint32", "length")
        (n,) = struct.unpack_from("<I", self.frame, start)
        element = min_size(self.edition, ftype)
        left = len(self.frame) - self.pos
        if n * element > left:
            if "length-overrun" not in self.off:
                raise FrameError("length-overrun", start, f"{path} claims {n} elements ({n * element} bytes at least), "
                                                          f"{left} bytes left")
            n = left // element if element else 0
        return n

    def value(self, ftype: FieldType, path: str):
        if ftype.array is not None:
            n = ftype.array if ftype.array >= 0 else self.count(path, ftype.element)
            if ftype.base == "uint8":
                start = self.take(n, path)
                self.mark(start, path, ftype.text(""))
                return self.frame[start:self.pos].hex()
            return [self.value(ftype.element, f"{path}[{i}]") for i in range(n)]
        if ftype.base in PRIMITIVES:
            code, size = PRIMITIVES[ftype.base]
            start = self.take(size, path)
            self.mark(start, path, ftype.base)
            if ftype.base in ("float32", "float64"):
                return float_from_bits(int.from_bytes(self.frame[start:self.pos], "little"), size)
            if ftype.base == "bool":
                return self.frame[start] != 0
            return int_form(struct.unpack_from("<" + code, self.frame, start)[0])
        if ftype.base == "string":
            n = self.count(path, FieldType("uint8"))
            start = self.take(n, path)
            self.mark(start, path, "string")
            return string_value(self.frame[start:self.pos])
        if ftype.base in TIME:
            start = self.take(8, path)
            self.mark(start, path, ftype.base)
            secs, nsecs = struct.unpack_from(TIME[ftype.base], self.frame, start)
            return {"secs": secs, "nsecs": nsecs}
        return self.fields(self.edition[ftype.base], path)
