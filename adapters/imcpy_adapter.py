"""Library adapter for imcpy (pybind11 bindings of DUNE's C++ IMC codec).

Messages move between the corpus's decoded form and imcpy message objects through one converter per
message definition, built once when the adapter is made; nothing here is specific to a message.
imcpy always emits little-endian frames (it decodes both orders), so encoding ``"be"`` is
``Unsupported``.

How imcpy's refusals become ``Rejected``:

* A setter refusing a value (pybind11 ``TypeError``): ``value-out-of-type`` for an integer that does
  not fit an integer field's C type, ``value-type`` for anything else. A value the decoded form
  cannot express at all (bad hex, a float string that is no float) is ``value-type`` as well.
* A typed inline field refusing a message (``RuntimeError`` "Failed to cast ...") or a typed
  message-list refusing an element (``TypeError``; this includes ``null``, which no imcpy list
  accepts): rule ``None``, imcpy's text in the reason.
* A field the definition does not have: ``unknown-field``; a message neither we nor imcpy know:
  ``unknown-message``. A message imcpy knows but the suite's definitions lack (or define with fields imcpy
  does not have) goes through its definition in the IMC.xml imcpy was built from (fetched once, on first need);
  one not even there is ``Unsupported`` on
  encode, and decodes to ``{"abbrev": <imcpy's name>, "fields": {}}`` (the header is kept at the top).
* Fields missing from the input keep imcpy's defaults: imcpy has no notion of a missing field.
* ``RuntimeError`` from DUNE's ``serialize``/``deserialize``: ``DUNE_ERRORS`` maps the start of its
  text to a rule. "invalid CRC" is ``crc`` and "invalid synchronization number" is ``sync``;
  "invalid message size" (only raised by ``serialize``) is ``size-limit``. "buffer is too short to
  be unpacked" (truncated header or payload, size beyond the data, a field overrunning the payload)
  and "invalid message identification number" (unknown or null id, top-level or inline) each stand
  for several corpus rules, so they carry rule ``None`` with DUNE's full text as the reason.

imcpy quirk: the plaintext getter returns a str in which every non-ASCII byte became U+FFFD (even
valid UTF-8: "é" reads back as two U+FFFD), so non-ASCII plaintext cannot be decoded faithfully.
The adapter reports the str imcpy gives; it does not recover the bytes from the frame.
"""

from __future__ import annotations

import struct
from math import isfinite
from operator import attrgetter

import imcpy

from imc_conformance.adapter_api import Rejected, Unsupported, installed_version
from imc_conformance.suites.imc.definitions import Definitions, FieldDef, MessageDef, load_definitions
from imc_conformance.kinds.vector.floats import float_from_bits, float_to_bits
from imc_conformance.suites.imc.values import raw_bytes, text_bytes

SUITE = "imc"

# Start of the text of a DUNE RuntimeError -> corpus rule (None: the text fits several rules).
DUNE_ERRORS = {
    "invalid CRC": "crc",
    "invalid synchronization number": "sync",
    "invalid message size": "size-limit",
    "buffer is too short to be unpacked": None,
    "invalid message identification number": None,
}

_BITS = {4: struct.Struct("<I"), 8: struct.Struct("<Q")}
_FLOATS = {4: struct.Struct("<f"), 8: struct.Struct("<d")}


def _dune_rule(text: str) -> str | None:
    for start, rule in DUNE_ERRORS.items():
        if text.startswith(start):
            return rule
    return None


def _first_line(exc: Exception) -> str:
    return str(exc).split("\n", 1)[0].removeprefix("(): ")


class _Converter:
    """Moves the fields of one message definition between the decoded form and imcpy objects."""

    def __init__(self, adapter: ImcpyAdapter, mdef: MessageDef):
        proto = imcpy.Factory.produce(mdef.abbrev)
        self.abbrev, self.cls = mdef.abbrev, type(proto)
        self.put, attrs, self.names, self.getters = {}, [], [], []
        self.plain = {}  # field -> (imcpy attribute, conversion or None): the fast way in, used while nothing fails
        for f in mdef.fields:
            # looked up on the class: reading an attribute may fail (erratum I6)
            attr = f.abbrev if hasattr(self.cls, f.abbrev) else f.abbrev.lower()
            if not hasattr(self.cls, attr):
                raise AttributeError(f"imcpy's {mdef.abbrev} has no attribute {f.abbrev!r} nor {attr!r}")
            where = f"{mdef.abbrev}.{f.abbrev}"
            self.put[f.abbrev] = adapter._putter(f, attr, where)
            self.plain[f.abbrev] = (attr, adapter._converter(f))
            attrs.append(attr)
            self.names.append(f.abbrev)
            self.getters.append(adapter._getter(f))
        self.attrs = attrs
        # one C-level call fetches every attribute (attrgetter of one name returns the bare value)
        self.fetch = attrgetter(*attrs) if len(attrs) > 1 else (lambda m, a=attrs: tuple(getattr(m, x) for x in a))
        # the fields whose values need converting (the others are taken as imcpy gives them)
        self.converted = [(i, name, get) for i, (name, get) in enumerate(zip(self.names, self.getters)) if get]

    def fill(self, msg, fields) -> None:
        if not isinstance(fields, dict):
            raise Rejected(f"{self.abbrev}: fields must be an object", rule="value-type")
        try:  # the fast way; on any trouble, again field by field, for the refusal the field's putter names
            plain = self.plain
            for name, value in fields.items():
                attr, convert = plain[name]
                setattr(msg, attr, convert(value) if convert is not None else value)
            return
        except Exception:  # noqa: BLE001 - only to take the careful way below
            pass
        for name, value in fields.items():
            put = self.put.get(name)
            if put is None:
                raise Rejected(f"{self.abbrev} has no field {name!r}", rule="unknown-field")
            put(msg, value)

    def fields(self, msg) -> dict:
        try:
            values = self.fetch(msg)
        except TypeError as exc:  # a getter whose C++ type the binding cannot convert (erratum I6)
            unreadable = next((n for n, a in zip(self.names, self.attrs) if not _readable(msg, a)), "?")
            raise Unsupported(f"imcpy's binding cannot return {self.abbrev}.{unreadable}: "
                              f"{_first_line(exc).split(' The signature')[0]}") from exc
        out = dict(zip(self.names, values))
        for i, name, get in self.converted:
            out[name] = get(values[i])
        return out


class ImcpyAdapter:
    """The runner's handle on imcpy: ``hello``, ``encode`` and ``decode`` over the decoded form."""

    def __init__(self, defs: Definitions | None = None):
        defs = defs or load_definitions()
        header = [FieldDef(abbrev=h["abbrev"], name=h["abbrev"], type=h["type"], clause="frame")
                  for h in defs.raw["frame"]["header"] if h["abbrev"] in defs.header_defaults]
        self._header_put = [
            (h.abbrev, defs.header_defaults[h.abbrev], self._putter(h, h.abbrev, f"header.{h.abbrev}")) for h in header
        ]
        self._header_names = [h.abbrev for h in header]
        self._header_plain = [(h.abbrev, defs.header_defaults[h.abbrev], h.abbrev) for h in header]
        self._header_getters = [self._getter(h) for h in header]
        self._header_fetch = attrgetter(*self._header_names)
        self._header_converted = [(i, h.abbrev, get) for i, (h, get) in enumerate(zip(header, self._header_getters)) if get]
        self._defs, self._whole = defs, None
        self._by_abbrev: dict[str, _Converter] = {}  # built on first use of each message
        self._by_class: dict[type, _Converter] = {}

    def _converter_of(self, abbrev: str) -> _Converter | None:
        """The converter of a message imcpy knows, built the first time from the suite's definition, else (the
        suite has none, or one whose fields imcpy lacks) from that of the IMC.xml imcpy was built from; None for
        a message imcpy does not know."""
        conv = self._by_abbrev.get(abbrev)
        if conv is not None:
            return conv
        try:
            imcpy.Factory.produce(abbrev)
        except (RuntimeError, TypeError):
            return None
        try:
            conv = _Converter(self, self._defs.by_abbrev[abbrev])
        except (KeyError, AttributeError):
            if self._whole is None:
                from imc_conformance.suites.imc.whole import imc_xml_definitions

                self._whole = imc_xml_definitions()
            mdef = self._whole.by_abbrev.get(abbrev)
            if mdef is None:
                return None
            conv = _Converter(self, mdef)
        self._by_abbrev[abbrev] = conv
        self._by_class[conv.cls] = conv
        return conv

    def hello(self) -> dict:
        return {"implementation": f"imcpy {installed_version(imcpy)} (DUNE C++ codec, IMC {imcpy.constants.VERSION})",
                "suites": [SUITE], "byte_orders": ["le"], "errata": "imcpy"}

    def encode(self, suite: str, message: dict, byte_order: str) -> bytes:
        _check_suite(suite)
        if byte_order != "le":
            raise Unsupported(f"imcpy only emits little-endian frames, not {byte_order!r}")
        msg = self._message_in(message)
        header = message.get("header", {})
        if not isinstance(header, dict):
            raise Rejected("header must be an object", rule="value-type")
        try:  # the fast way, as for fields
            for name, default, attr in self._header_plain:
                setattr(msg, attr, header.get(name, default))
        except Exception:  # noqa: BLE001 - only to take the careful way below
            for name, default, put in self._header_put:
                put(msg, header.get(name, default))
        try:
            return msg.serialize()
        except RuntimeError as exc:
            raise Rejected(str(exc), rule=_dune_rule(str(exc))) from exc

    def decode(self, suite: str, frame: bytes) -> dict:
        _check_suite(suite)
        try:
            msg = imcpy.Packet.deserialize(frame)
        except RuntimeError as exc:
            raise Rejected(str(exc), rule=_dune_rule(str(exc))) from exc
        out = self._message_out(msg)
        values = self._header_fetch(msg)
        header = dict(zip(self._header_names, values))
        for i, name, get in self._header_converted:
            header[name] = get(values[i])
        return {"abbrev": out["abbrev"], "header": header, "fields": out["fields"]}

    # ------------------------------------------------------------ decoded form -> imcpy

    def _message_in(self, message):
        """A new imcpy message holding the fields (not the header) of a decoded-form message."""
        if not isinstance(message, dict):
            raise Rejected("a message must be an object", rule="value-type")
        abbrev = message.get("abbrev")
        conv = self._converter_of(abbrev) if isinstance(abbrev, str) else None
        if conv is None:
            try:
                imcpy.Factory.produce(abbrev)
            except (RuntimeError, TypeError) as exc:
                raise Rejected(f"imcpy does not know message {abbrev!r}: {_first_line(exc)}",
                               rule="unknown-message") from exc
            raise Unsupported(f"imcpy knows {abbrev} but neither the definitions nor its IMC.xml do")
        msg = conv.cls()
        conv.fill(msg, message.get("fields", {}))
        return msg

    def _inline_in(self, value):
        if value is None:
            return None
        if not isinstance(value, dict):
            raise ValueError("an inline message must be an object or null")
        return self._message_in(value)

    def _converter(self, f: FieldDef):
        """The conversion of a field's decoded value to what imcpy's setter takes (None: as it is)."""
        if f.type == "message-list":
            def convert_list(value):
                if not isinstance(value, list):
                    raise ValueError("a message-list must be an array")
                return [self._inline_in(element) for element in value]
            return convert_list
        if f.is_float:
            # For fp32 the f32 bit pattern is widened to a Python float (a double); that conversion quiets a
            # signalling NaN, so such payloads cannot reach imcpy intact.
            width, bits, floats = f.size, _BITS[f.size], _FLOATS[f.size]
            return lambda value: floats.unpack(bits.pack(float_to_bits(value, width)))[0] if isinstance(value, str) else value
        return {"plaintext": text_bytes, "rawdata": raw_bytes, "message": self._inline_in}.get(f.type)

    def _putter(self, f: FieldDef, attr: str, where: str):
        """A function (imcpy message, decoded value) -> None storing one field, raising Rejected."""
        if f.type == "message-list":
            def put_list(msg, value):
                if not isinstance(value, list):
                    raise Rejected(f"{where}: a message-list must be an array", rule="value-type")
                items = getattr(msg, attr)
                for element in value:
                    try:
                        items.append(self._inline_in(element))
                    except ValueError as exc:
                        raise Rejected(f"{where}: {exc}", rule="value-type") from exc
                    except TypeError as exc:
                        raise Rejected(f"{where}: imcpy refused element {_name(element)} "
                                       f"({_first_line(exc)})") from exc
            return put_list

        convert = self._converter(f)

        def put(msg, value):
            try:
                setattr(msg, attr, convert(value) if convert else value)
            except ValueError as exc:
                raise Rejected(f"{where}: {exc}", rule="value-type") from exc
            except (TypeError, RuntimeError) as exc:
                if f.type == "message":
                    raise Rejected(f"{where}: imcpy refused {_name(value)} ({_first_line(exc)})") from exc
                rule = "value-out-of-type" if f.is_int and type(value) is int else "value-type"
                raise Rejected(f"{where}: imcpy refused {value!r} ({_first_line(exc)})", rule=rule) from exc
        return put

    # ------------------------------------------------------------ imcpy -> decoded form

    def _message_out(self, msg) -> dict:
        conv = self._by_class.get(type(msg)) or self._converter_of(msg.msg_name)
        if conv is None:
            return {"abbrev": msg.msg_name, "fields": {}}
        return {"abbrev": conv.abbrev, "fields": conv.fields(msg)}

    def _inline_out(self, msg):
        return None if msg is None else self._message_out(msg)

    def _getter(self, f: FieldDef):
        """A function turning the value of an imcpy attribute into the field's decoded form (None: as is)."""
        if f.is_float:
            width, bits, floats = f.size, _BITS[f.size], _FLOATS[f.size]
            # Finite values are returned as imcpy gives them (exact at the field's width, which is how the
            # runner compares); NaN and infinities take their canonical string form.
            return lambda x: x if isfinite(x) else float_from_bits(bits.unpack(floats.pack(x))[0], width)
        if f.is_int:
            return int if f.enum_kind == "enum" else None  # enum getters return pybind11 enums; others are ints
        return {
            "plaintext": None,  # already a str (lossy, see the module docstring)
            "rawdata": bytes.hex,
            "message": self._inline_out,
            "message-list": lambda items: [self._inline_out(m) for m in items],  # null elements read as None
        }[f.type]


def _readable(msg, attr: str) -> bool:
    try:
        getattr(msg, attr)
    except TypeError:
        return False
    return True


def _name(value) -> str:
    return repr(value.get("abbrev")) if isinstance(value, dict) else repr(value)


def _check_suite(suite: str) -> None:
    if suite != SUITE:
        raise Unsupported(f"imcpy implements only the {SUITE!r} suite, not {suite!r}")


def adapter() -> ImcpyAdapter:
    return ImcpyAdapter()
