"""A reference ROS 1 adapter over the suite's own codec, and mutants of it with one seeded bug each.

Most mutants change the definitions the implementation holds (what a real package drift does: a Header
without seq, as armw's native middleware has; float32 read as float64; a fixed array taken for a
variable one); the others change what it does with bytes or texts.
"""

from __future__ import annotations

import dataclasses
import hashlib
import struct

from imc_conformance.adapter_api import Rejected
from imc_conformance.suites.ros_acomms import codec
from imc_conformance.suites.ros_acomms.definitions import Edition, FieldType, Message, load_definitions
from imc_conformance.suites.ros_acomms.msgtext import full_text, md5, msg_text, service_md5

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


class Float32AsFloat64(Reference):
    """Every float32 field is a float64."""

    name = "float32-as-float64"

    def definitions(self, view):
        return retyped(view, lambda full, f: dataclasses.replace(f, type=dataclasses.replace(f.type, base="float64"))
                       if f.type.base == "float32" else f)


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


class RefusesTrailingBytes(Reference):
    """Refuses bytes after the message (rosbags does): implementation-defined, so it must survive."""

    name = "refuses-trailing-bytes"

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


MUTANTS = (HeaderWithoutSeq, Float32AsFloat64, FixedArraysWithCount, AcceptsTruncation, ZeroesImpossibleLengths,
           WrapsIntegers, SignedTimeSeconds, SortedMd5, DefinitionWithoutDependencies, RefusesTrailingBytes)
