"""A reference ROS 1 adapter over the suite's own codec, and mutants of it with one seeded bug each.

Most mutants change the definitions the implementation holds (what a real package drift does: a Header
without seq, as armw's native middleware has; float32 read as float64; a fixed array taken for a
variable one); the others change what it does with bytes or texts.
"""

from __future__ import annotations

import dataclasses
import hashlib
import struct

from ...adapter_api import Rejected
from . import codec
from .definitions import Edition, FieldType, Message, load_definitions
from .msgtext import full_text, md5, msg_text, service_md5

DEFS = load_definitions()


class Reference:
    """A correct library adapter: the suite's codec, MD5 and texts, under one edition's definitions."""

    name = "reference"

    def __init__(self, edition: str = "seed"):
        self.view = self.definitions(DEFS.edition(edition))

    def definitions(self, view: Edition) -> Edition:
        return view

    def hello(self) -> dict:
        return {"implementation": f"ros mutant {self.name}", "suites": ["ros_acomms"], "encodings": ["ros1"]}

    def encode(self, suite, message, encoding):
        try:
            return codec.encode(self.view, message, encoding)
        except codec.EncodeError as exc:
            raise Rejected(exc.detail, exc.rule) from exc

    def decode(self, suite, frame, type="", encoding="ros1"):
        try:
            return codec.decode(self.view, type, frame)
        except codec.FrameError as exc:
            raise Rejected(exc.detail, exc.rule) from exc

    def describe(self, suite, type=""):
        message = self.view[type]
        out = {"md5": self.md5(message), "definition": full_text(self.view, message)}
        d = message.definition
        halves = [f"{d.package}/{d.service}{h}" for h in ("Request", "Response")] if d.service else []
        if halves and all(h in self.view for h in halves):
            out["service_md5"] = service_md5(self.view, *(self.view[h] for h in halves))
        return out

    def md5(self, message: Message) -> str:
        return md5(self.view, message)


def retyped(view: Edition, change) -> Edition:
    """The edition with ``change(message_full_name, field) -> Field | None`` applied to every field (None drops it)."""
    types = {}
    for full, m in view.types.items():
        fields = tuple(f2 for f in m.fields if (f2 := change(full, f)) is not None)
        types[full] = dataclasses.replace(m, fields=fields)
    return Edition(view.name, types)


class HeaderWithoutSeq(Reference):
    """Its std_msgs/Header lacks seq, as armw's native middleware has it: 4 bytes short in every Header type."""

    name = "header-without-seq"

    def definitions(self, view):
        return retyped(view, lambda full, f: None if full == "std_msgs/Header" and f.name == "seq" else f)


def rebased(view: Edition, old: str, new: str) -> Edition:
    """The edition with every field (arrays included) of builtin ``old`` taken for ``new``."""
    return retyped(view, lambda full, f: dataclasses.replace(f, type=dataclasses.replace(f.type, base=new))
                   if f.type.base == old else f)


class Float32AsFloat64(Reference):
    """Every float32 field is a float64."""

    name = "float32-as-float64"

    def definitions(self, view):
        return rebased(view, "float32", "float64")


class FixedArraysWithCount(Reference):
    """Takes T[N] for T[]: writes a count before a fixed array, and encodes any length."""

    name = "fixed-arrays-with-count"

    def definitions(self, view):
        return retyped(view, lambda full, f: dataclasses.replace(f, type=FieldType(f.type.base, -1))
                       if f.type.array is not None and f.type.array >= 0 else f)


class AcceptsTruncation(Reference):
    """Reads missing bytes as zeros: a truncated message, or a length past the data, decodes."""

    name = "accepts-truncation"

    def decode(self, suite, frame, type="", encoding="ros1"):
        try:
            return super().decode(suite, frame, type, encoding)
        except Rejected:
            return super().decode(suite, bytes(frame) + bytes(4096), type, encoding)


class ZeroesImpossibleLengths(Reference):
    """Takes a length that claims more than the bytes left for an empty string or array."""

    name = "zeroes-impossible-lengths"

    def decode(self, suite, frame, type="", encoding="ros1"):
        frame = bytes(frame)
        for _ in range(16):
            try:
                return codec.decode(self.view, type, frame)
            except codec.FrameError as exc:
                if exc.rule != "length-overrun":
                    raise Rejected(exc.detail, exc.rule) from exc
                frame = frame[:exc.offset] + bytes(4) + frame[exc.offset + 4:]
        raise Rejected("too many impossible lengths")


class WrapsIntegers(Reference):
    """Encodes an integer its field cannot hold modulo the field's width instead of refusing it."""

    name = "wraps-integers"
    equivalent = ("the ROS 1 documentation does not say an encoder must refuse such a value: writing its low-order bits "
                  "is a permitted outcome (class value-out-of-type, truncate)")

    def encode(self, suite, message, encoding):
        return super().encode(suite, wrap(self.view, message), encoding)


class SignedTimeSeconds(Reference):
    """Takes time's seconds for int32 (rosbags' erratum R1)."""

    name = "signed-time-seconds"

    def decode(self, suite, frame, type="", encoding="ros1"):
        return map_times(super().decode(suite, frame, type, encoding),
                         lambda t: dict(t, secs=struct.unpack("<i", struct.pack("<I", t["secs"]))[0]))


class SortedMd5(Reference):
    """Computes the MD5 over the fields sorted by name (not the ROS 1 canonical order)."""

    name = "sorted-md5"

    def md5(self, message):
        lines = sorted(f"{f.type.text('')} {f.name}" for f in message.fields)
        return hashlib.md5("\n".join(lines).encode()).hexdigest()


class DefinitionWithoutDependencies(Reference):
    """Describes a type by its own text only, without the MSG: sections of the types it nests."""

    name = "definition-without-dependencies"

    def describe(self, suite, type=""):
        return dict(super().describe(suite, type), definition=msg_text(self.view[type]))


# ---------------------------------------------------------------- more seeded bugs (the fuzzing issue's set)

class ValueMutant(Reference):
    """Base of the decoders that alter decoded values: ``change(field type, value)`` for every field, nested ones
    and array elements included."""

    def decode(self, suite, frame, type="", encoding="ros1"):
        message = super().decode(suite, frame, type, encoding)
        return {"type": message["type"], "fields": self._fields(message["type"], message["fields"])}

    def _fields(self, full, fields):
        return {f.name: self._value(f.type, fields[f.name]) for f in self.view[full].fields}

    def _value(self, ftype, value):
        if ftype.array is not None and ftype.base != "uint8":
            value = [self._value(ftype.element, v) for v in value]
        elif ftype.array is None and not ftype.is_builtin:
            value = self._fields(ftype.base, value)
        return self.change(ftype, value)

    def change(self, ftype, value):
        return value


class StringLengthCountsTerminator(Reference):
    """The encoder writes a string's length one too large (it counts a NUL it does not send)."""

    name = "string-length-counts-terminator"

    def encode(self, suite, message, encoding):
        frame = bytearray(super().encode(suite, message, encoding))
        spans = codec.layout(self.view, message["type"], bytes(frame))
        strings = {s.path for s in spans if s.type == "string"}
        for span in spans:
            if span.role == "length" and span.path[:-len(".length")] in strings:
                (n,) = struct.unpack_from("<I", frame, span.start)
                struct.pack_into("<I", frame, span.start, n + 1)
        return bytes(frame)


class Md5OfRenamedField(Reference):
    """The MD5 is computed from a definition whose first field is renamed (a stale generated file)."""

    name = "md5-of-renamed-field"

    def md5(self, message):
        if not message.fields:
            return super().md5(message)
        first = dataclasses.replace(message.fields[0], name=message.fields[0].name + "_")
        return md5(self.view, dataclasses.replace(message, fields=(first, *message.fields[1:])))


class Uint64ReadSigned(ValueMutant):
    """uint64 values from 2^63 decode negative (read as int64)."""

    name = "uint64-read-signed"

    def change(self, ftype, value):
        number = codec.int_value(value) if ftype.base == "uint64" and ftype.array is None else None
        return codec.int_form(number - (1 << 64)) if number is not None and number >= 1 << 63 else value


class Uint16ReadSigned(ValueMutant):
    """uint16 values from 32768 decode negative (read as int16)."""

    name = "uint16-read-signed"

    def change(self, ftype, value):
        return value - 65536 if ftype.base == "uint16" and ftype.array is None and value >= 32768 else value


class BoolOnlyOneIsTrue(ValueMutant):
    """A bool byte other than 0 and 1 decodes as false (the test is == 1, not != 0)."""

    name = "bool-only-one-is-true"

    def decode(self, suite, frame, type="", encoding="ros1"):
        message = super().decode(suite, frame, type, encoding)
        spans = codec.layout(self.view, type, bytes(frame))
        odd = {s.path for s in spans if s.type == "bool" and frame[s.start] > 1}
        if not odd:
            return message
        fields = dict(message["fields"])
        for path in odd:  # top-level bools (the corpus's bool-byte cases)
            name = path.split(".", 1)[1]
            if name in fields:
                fields[name] = False
        return dict(message, fields=fields)


class TimeNsecsFirst(Reference):
    """time and duration are written and read as nsecs then secs."""

    name = "time-nsecs-first"

    def encode(self, suite, message, encoding):
        return super().encode(suite, map_times(message, lambda t: {"secs": t["nsecs"], "nsecs": t["secs"]})
                              if self._times_fit(message) else message, encoding)

    def decode(self, suite, frame, type="", encoding="ros1"):
        return map_times(super().decode(suite, frame, type, encoding), lambda t: {"secs": t["nsecs"], "nsecs": t["secs"]})

    @staticmethod
    def _times_fit(message) -> bool:
        fits = []
        map_times(message, lambda t: fits.append(0 <= t["nsecs"] <= 0xFFFFFFFF and t["secs"] >= -(1 << 31)) or t)
        return all(fits)


class StringArrayDropsEmpty(ValueMutant):
    """Empty strings of a string[] are dropped on decode (a split that skips empty parts)."""

    name = "string-array-drops-empty"

    def change(self, ftype, value):
        return [v for v in value if v != ""] if ftype.base == "string" and ftype.array is not None else value


class Int8AsUint8(Reference):
    """Every int8 field is a uint8 (negative values refused on encode, read back positive)."""

    name = "int8-as-uint8"

    def definitions(self, view):
        return rebased(view, "int8", "uint8")


class DropsFifthArrayElement(ValueMutant):
    """A variable array of exactly five elements (not uint8[]) decodes without its last one."""

    name = "drops-fifth-array-element"

    def change(self, ftype, value):
        return value[:4] if ftype.array is not None and ftype.array < 0 and ftype.base != "uint8" \
            and len(value) == 5 else value


class StringCharacterLength(Reference):
    """The encoder writes a string's length in characters, not bytes: wrong for non-ASCII text."""

    name = "string-character-length"

    def encode(self, suite, message, encoding):
        frame = bytearray(super().encode(suite, message, encoding))
        decoded = codec.decode(self.view, message["type"], bytes(frame))
        texts = {}
        _collect_strings(self.view, message["type"], decoded["fields"], self.view[message["type"]].name, texts)
        for span in codec.layout(self.view, message["type"], bytes(frame)):
            owner = span.path[:-len(".length")] if span.role == "length" else None
            if owner in texts and isinstance(texts[owner], str):
                struct.pack_into("<I", frame, span.start, len(texts[owner]))
        return bytes(frame)


class NanPayloadLost(ValueMutant):
    """Every NaN decodes as the default quiet NaN (its payload and sign lost)."""

    name = "nan-payload-lost"

    def change(self, ftype, value):
        return "nan" if ftype.base in ("float32", "float64") and isinstance(value, str) and value.startswith("nan") else value


class RefusesTrailingBytes(Reference):
    """Refuses bytes after the message (rosbags does): implementation-defined, so it must survive."""

    name = "refuses-trailing-bytes"
    equivalent = "bytes after a message are implementation-defined (acceptable cases): refusing them is conforming"

    def decode(self, suite, frame, type="", encoding="ros1"):
        message = super().decode(suite, frame, type, encoding)
        if len(codec.encode(self.view, message)) != len(frame):
            raise Rejected("bytes after the message")
        return message


def wrap(view: Edition, message: dict) -> dict:
    """``message`` with every integer out of its field's range wrapped to the width (top-level fields)."""
    out = {"type": message["type"], "fields": dict(message["fields"])}
    for f in view[message["type"]].fields:
        value = out["fields"].get(f.name)
        number = codec.int_value(value) if f.type.array is None and f.type.base in ("int8", "uint8", "int16", "uint16",
                                                                                   "int32", "uint32", "int64", "uint64") else None
        if number is not None:
            lo, hi = codec.int_bounds(f.type.base)
            span = hi - lo + 1
            out["fields"][f.name] = codec.int_form((number - lo) % span + lo)
    return out


def map_times(value, change):
    """``value`` with ``change`` applied to every ``{secs, nsecs}`` object in it."""
    if isinstance(value, dict):
        if set(value) == {"secs", "nsecs"}:
            return change(value)
        return {k: map_times(v, change) for k, v in value.items()}
    if isinstance(value, list):
        return [map_times(v, change) for v in value]
    return value


def _collect_strings(view: Edition, full: str, fields: dict, path: str, out: dict) -> None:
    """Every string value of a decoded message by its layout path (``Type.field``, ``Type.list[0].field``)."""
    for f in view[full].fields:
        value, here = fields[f.name], f"{path}.{f.name}"
        if f.type.base == "string":
            if f.type.array is None:
                out[here] = value
            else:
                out.update({f"{here}[{i}]": v for i, v in enumerate(value)})
        elif not f.type.is_builtin:
            items = value if f.type.array is not None else [value]
            for i, item in enumerate(items):
                _collect_strings(view, f.type.base, item, f"{here}[{i}]" if f.type.array is not None else here, out)


MUTANTS = (HeaderWithoutSeq, Float32AsFloat64, FixedArraysWithCount, AcceptsTruncation, ZeroesImpossibleLengths,
           WrapsIntegers, SignedTimeSeconds, SortedMd5, DefinitionWithoutDependencies, RefusesTrailingBytes,
           StringLengthCountsTerminator, Md5OfRenamedField, Uint64ReadSigned, Uint16ReadSigned, BoolOnlyOneIsTrue,
           TimeNsecsFirst, StringArrayDropsEmpty, Int8AsUint8, DropsFifthArrayElement, StringCharacterLength, NanPayloadLost)
NEW = MUTANTS[MUTANTS.index(StringLengthCountsTerminator):]  # added with the fuzzer
