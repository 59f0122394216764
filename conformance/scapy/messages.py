"""The message classes, generated from the IMC definitions on first use, and the fields holding messages."""

from __future__ import annotations

import struct
from functools import cache

from scapy.compat import raw
from scapy.fields import Field
from scapy.packet import Packet

from ..suites import load_suite
from ..suites.imc.definitions import SCALAR_FORMATS, FieldDef, MessageDef
from .byteorder import prefix
from .fields import Data, Enum, Flags, Float, Number, Text


class Message(Packet):
    """Base of the generated message classes; ``definition`` is the message's MessageDef."""

    definition: MessageDef

    def do_dissect(self, s: bytes) -> bytes:
        rest = super().do_dissect(s)
        self.raw_packet_cache = None  # rebuild from the values, in the byte order of the frame built
        return rest

    def decoded_fields(self) -> dict:
        """The message's fields in the decoded form."""
        return {f.name: f.i2d(self.getfieldval(f.name)) for f in self.fields_desc}

    @classmethod
    def from_decoded_fields(cls, fields: dict) -> Message:
        """The message with these fields (decoded form); fields not given keep their defaults."""
        by_name = {f.name: f for f in cls.fields_desc}
        return cls(**{name: by_name[name].d2i(value) for name, value in fields.items()})


class NullMessage(Packet):
    """The null message (id 65535, nothing follows), standing for None in a message-list."""

    name = "null message"


_chosen: list = []  # the definitions use_definitions chose, if it was called


def definitions():
    """The definitions the layer dissects and builds with: the IMC suite's (the seeds' messages), unless
    ``use_definitions`` chose others."""
    return _chosen[0] if _chosen else load_suite("imc").defs


def choose(defs) -> None:
    """Generate message classes from ``defs`` from now on (``imc_conformance.scapy.use_definitions``)."""
    _chosen[:] = [defs]
    _generated.cache_clear()


def message_class(key: int | str) -> type[Message]:
    """The class of the message with this id or abbreviation, generated on first use; KeyError if none."""
    return _generated(definitions()[key].abbrev)


def __getattr__(name: str) -> type[Message]:
    """The generated classes as attributes of this module, so that their packets pickle."""
    try:
        return message_class(name)
    except KeyError:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None


@cache
def _generated(abbrev: str) -> type[Message]:
    mdef = definitions().by_abbrev[abbrev]
    return type(abbrev, (Message,), {"__module__": __name__, "name": abbrev, "definition": mdef,
                                     "fields_desc": [field_of(f) for f in mdef.fields]})


def field_of(f: FieldDef) -> Field:
    """The scapy field of a message field."""
    if f.is_float:
        return Float(f.abbrev, 0.0, f.size, f.unit)
    if f.is_int:
        names = {v.value: v.abbrev for v in f.enum_values}
        kind = {"enum": Enum, "bitfield": Flags}.get(f.enum_kind)
        if kind is Flags:  # scapy names single bits only (IMC.xml's tables also name 0 and masks)
            names = {value: name for value, name in names.items() if value > 0 and not value & (value - 1)}
        code = SCALAR_FORMATS[f.type]
        return kind(f.abbrev, 0, code, names) if kind else Number(f.abbrev, 0, code, f.unit)
    return {"plaintext": Text, "rawdata": Data, "message": InlineMessage, "message-list": MessageList}[f.type](f.abbrev)


def read_inline(s: bytes) -> tuple[bytes, Message | None]:
    """An inline message from the start of ``s`` (None for the null id) and the bytes after it."""
    (mgid,) = struct.unpack(prefix() + "H", s[:2])
    if mgid == definitions().null_id:
        return s[2:], None
    message = message_class(mgid)()
    return message.do_dissect(s[2:]), message


def write_inline(message: Message | NullMessage | None) -> bytes:
    if message is None or isinstance(message, NullMessage):
        return struct.pack(prefix() + "H", definitions().null_id)
    return struct.pack(prefix() + "H", message.definition.id) + raw(message)


def inline_decoded(message: Message | NullMessage | None) -> dict | None:
    if message is None or isinstance(message, NullMessage):
        return None
    return {"abbrev": message.definition.abbrev, "fields": message.decoded_fields()}


def inline_from_decoded(value: dict | None) -> Message | None:
    return None if value is None else message_class(value["abbrev"]).from_decoded_fields(value.get("fields", {}))


class InlineMessage(Field):
    """An inline message: its u16 id, then its fields; the value is a message, or None for the null id."""

    holds_packets = 1

    def __init__(self, name: str):
        Field.__init__(self, name, None)

    def addfield(self, pkt, s: bytes, val) -> bytes:
        return s + write_inline(val)

    def getfield(self, pkt, s: bytes):
        return read_inline(s)

    def i2d(self, x):
        return inline_decoded(x)

    def d2i(self, value):
        return inline_from_decoded(value)


class MessageList(Field):
    """A message-list: a u16 count, then that many inline messages; a null one is a NullMessage (None is
    accepted on assignment)."""

    holds_packets = 1
    islist = 1

    def __init__(self, name: str):
        Field.__init__(self, name, [])

    def any2i(self, pkt, x) -> list:
        return [NullMessage() if m is None else m for m in x]

    def addfield(self, pkt, s: bytes, val) -> bytes:
        return s + struct.pack(prefix() + "H", len(val)) + b"".join(write_inline(m) for m in val)

    def getfield(self, pkt, s: bytes):
        (count,) = struct.unpack(prefix() + "H", s[:2])
        s, messages = s[2:], []
        for _ in range(count):
            s, message = read_inline(s)
            messages.append(NullMessage() if message is None else message)
        return s, messages

    def i2d(self, x) -> list:
        return [inline_decoded(m) for m in x]

    def d2i(self, value) -> list:
        return [inline_from_decoded(v) for v in value]
