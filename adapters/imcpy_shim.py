"""imcpy (DUNE's C++ IMC codec) behind the subprocess adapter protocol; standard library and imcpy only.

Usage: ``python adapters/imcpy_shim.py [--definitions PATH]``. Reads one JSON request per line on
stdin and writes one JSON answer per line on stdout (protocol: ``imc_conformance.sessions.subprocess``):
``{"id", "ok": true, ...}``, a refusal ``{"id", "ok": false, "error", "rule"?}``, an absent capability
``{"id", "ok": false, "unsupported": true, "error"}``, and ``{"id", "ok": false, "internal": true,
"error"}`` when the shim itself fails (an adapter error, never the implementation's refusal).

It behaves as the imcpy library adapter does, quirks included, but shares no code with it: field
order and types come from ``vectors/imc/definitions.json`` (next to this file's parent folder, or
``--definitions``) and one converter per message is built at start. imcpy emits little-endian only
(``be`` is unsupported); its plaintext getter turns every non-ASCII byte into U+FFFD and the shim
reports that str; a value a setter refuses (UNSUPPORTED = 666 in a uint8) is refused; a field whose getter
has no Python type (IMC.xml's Boolean enumeration: Sample.syringe0, GetWorldCoordinates.tracking) makes a decode
unsupported. For ``--suite imc-full`` the runner passes the whole protocol's definitions. DUNE's error
texts map to rules: "invalid CRC" -> ``crc``, "invalid synchronization number" -> ``sync``, "invalid
message size" -> ``size-limit``, anything else no rule. Floats are answered at their width without
shortest-decimal canonicalisation; ``nan``/``inf``/``-inf``, ``-0.0`` and NaN payloads are kept.
"""

from __future__ import annotations

import argparse
import json
import sys
from importlib.metadata import version
from pathlib import Path

import imcpy
from shim_protocol import FLOAT, Refused, Unsupported, float_bits, float_value, serve

DEFINITIONS = Path(__file__).resolve().parent.parent / "vectors" / "imc" / "definitions.json"
SUITE = "imc"
DUNE_ERRORS = {"invalid CRC": "crc", "invalid synchronization number": "sync", "invalid message size": "size-limit"}


# ---------------------------------------------------------------- decoded-form values

def text_bytes(value) -> bytes:
    if isinstance(value, str):
        return value.encode("utf-8")
    if isinstance(value, dict) and set(value) == {"hex"}:
        return bytes.fromhex(value["hex"])
    raise ValueError(f"{value!r} is not a plaintext value")


def raw_bytes(value) -> bytes:
    if not isinstance(value, str):
        raise ValueError(f"{value!r} is not rawdata hex")
    return bytes.fromhex(value)


# ---------------------------------------------------------------- definitions

class Field:
    """One field of the definitions: its name, wire type and the type's kind and size."""

    def __init__(self, abbrev: str, ftype: str, types: dict):
        self.abbrev, self.type = abbrev, ftype
        self.kind, self.size = types[ftype]["kind"], types[ftype].get("size")

    @property
    def is_int(self) -> bool:
        return self.kind in ("int", "uint")


def dune_rule(text: str) -> str | None:
    return next((rule for start, rule in DUNE_ERRORS.items() if text.startswith(start)), None)


def first_line(exc: Exception) -> str:
    return str(exc).split("\n", 1)[0].removeprefix("(): ")


def name_of(value) -> str:
    return repr(value.get("abbrev")) if isinstance(value, dict) else repr(value)


class Converter:
    """Moves the fields of one message between the decoded form and imcpy objects."""

    def __init__(self, shim: ImcpyShim, abbrev: str, fields: list[Field]):
        proto = imcpy.Factory.produce(abbrev)
        self.abbrev, self.cls, self.put, self.get = abbrev, type(proto), {}, []
        for f in fields:  # looked up on the class: reading some attributes fails (Boolean fields, below)
            attr = f.abbrev if hasattr(self.cls, f.abbrev) else f.abbrev.lower()
            if not hasattr(self.cls, attr):
                raise AttributeError(f"imcpy's {abbrev} has no attribute {f.abbrev!r} nor {attr!r}")
            self.put[f.abbrev] = shim.putter(f, attr, f"{abbrev}.{f.abbrev}")
            self.get.append((f.abbrev, attr, shim.getter(f)))

    def fill(self, msg, fields) -> None:
        if not isinstance(fields, dict):
            raise Refused(f"{self.abbrev}: fields must be an object", rule="value-type")
        for name, value in fields.items():
            put = self.put.get(name)
            if put is None:
                raise Refused(f"{self.abbrev} has no field {name!r}", rule="unknown-field")
            put(msg, value)

    def fields(self, msg) -> dict:
        out = {}
        for name, attr, get in self.get:
            try:
                value = getattr(msg, attr)
            except TypeError as exc:  # imcpy's binding has no Python type for DUNE's Boolean enumeration
                raise Unsupported(f"imcpy's binding cannot return {self.abbrev}.{name}: "
                                  f"{first_line(exc).split(' The signature')[0]}") from exc
            out[name] = get(value)
        return out


class ImcpyShim:
    """hello / encode / decode over imcpy in the decoded form, generic over the definitions."""

    def __init__(self, definitions: dict):
        types, frame = definitions["types"], definitions["frame"]
        defaults = {k: v for k, v in frame["header_defaults"].items() if k != "source"}
        header = [Field(h["abbrev"], h["type"], types) for h in frame["header"] if h["abbrev"] in defaults]
        self.header_put = [(h.abbrev, defaults[h.abbrev], self.putter(h, h.abbrev, f"header.{h.abbrev}"))
                           for h in header]
        self.header_get = [(h.abbrev, self.getter(h)) for h in header]
        self.by_abbrev = {m["abbrev"]: Converter(self, m["abbrev"], [Field(f["abbrev"], f["type"], types)
                                                                     for f in m["fields"]])
                          for m in definitions["messages"]}
        self.by_class = {c.cls: c for c in self.by_abbrev.values()}

    def hello(self) -> dict:
        return {"implementation": f"imcpy {version('imcpy')} (DUNE C++ codec, IMC {imcpy.constants.VERSION})",
                "suites": [SUITE], "byte_orders": ["le"], "errata": "imcpy"}

    def encode(self, suite: str, message, byte_order: str) -> bytes:
        check_suite(suite)
        if byte_order != "le":
            raise Unsupported(f"imcpy only emits little-endian frames, not {byte_order!r}")
        msg = self.message_in(message)
        header = message.get("header", {})
        if not isinstance(header, dict):
            raise Refused("header must be an object", rule="value-type")
        for name, default, put in self.header_put:
            put(msg, header.get(name, default))
        try:
            return msg.serialize()
        except RuntimeError as exc:
            raise Refused(str(exc), rule=dune_rule(str(exc))) from exc

    def decode(self, suite: str, frame: bytes) -> dict:
        check_suite(suite)
        try:
            msg = imcpy.Packet.deserialize(frame)
        except RuntimeError as exc:
            raise Refused(str(exc), rule=dune_rule(str(exc))) from exc
        out = self.message_out(msg)
        header = {name: get(getattr(msg, name)) for name, get in self.header_get}
        return {"abbrev": out["abbrev"], "header": header, "fields": out["fields"]}

    # ------------------------------------------------------------ decoded form -> imcpy

    def message_in(self, message):
        if not isinstance(message, dict):
            raise Refused("a message must be an object", rule="value-type")
        abbrev = message.get("abbrev")
        conv = self.by_abbrev.get(abbrev) if isinstance(abbrev, str) else None
        if conv is None:
            try:
                imcpy.Factory.produce(abbrev)
            except (RuntimeError, TypeError) as exc:
                raise Refused(f"imcpy does not know message {abbrev!r}: {first_line(exc)}",
                              rule="unknown-message") from exc
            raise Unsupported(f"imcpy knows {abbrev} but the definitions do not")
        msg = conv.cls()
        conv.fill(msg, message.get("fields", {}))
        return msg

    def inline_in(self, value):
        if value is None:
            return None
        if not isinstance(value, dict):
            raise ValueError("an inline message must be an object or null")
        return self.message_in(value)

    def putter(self, f: Field, attr: str, where: str):
        """A function (imcpy message, decoded value) -> None storing one field, raising Refused."""
        if f.kind == "list":
            return self.list_putter(attr, where)
        convert = {"float": lambda v: float_in(v, f.size), "text": text_bytes, "bytes": raw_bytes,
                   "inline": self.inline_in}.get(f.kind)

        def put(msg, value):
            try:
                setattr(msg, attr, convert(value) if convert else value)
            except ValueError as exc:
                raise Refused(f"{where}: {exc}", rule="value-type") from exc
            except (TypeError, RuntimeError) as exc:
                if f.kind == "inline":
                    raise Refused(f"{where}: imcpy refused {name_of(value)} ({first_line(exc)})") from exc
                rule = "value-out-of-type" if f.is_int and type(value) is int else "value-type"
                raise Refused(f"{where}: imcpy refused {value!r} ({first_line(exc)})", rule=rule) from exc
        return put

    def list_putter(self, attr: str, where: str):
        def put_list(msg, value):
            if not isinstance(value, list):
                raise Refused(f"{where}: a message-list must be an array", rule="value-type")
            items = getattr(msg, attr)
            for element in value:
                try:
                    items.append(self.inline_in(element))
                except ValueError as exc:
                    raise Refused(f"{where}: {exc}", rule="value-type") from exc
                except TypeError as exc:
                    raise Refused(f"{where}: imcpy refused element {name_of(element)} ({first_line(exc)})") from exc
        return put_list

    # ------------------------------------------------------------ imcpy -> decoded form

    def message_out(self, msg) -> dict:
        conv = self.by_class.get(type(msg))
        if conv is None:
            return {"abbrev": msg.msg_name, "fields": {}}
        return {"abbrev": conv.abbrev, "fields": conv.fields(msg)}

    def inline_out(self, msg):
        return None if msg is None else self.message_out(msg)

    def getter(self, f: Field):
        """A function turning an imcpy attribute's value into the field's decoded form."""
        if f.kind == "float":
            return lambda x: float_value(x, f.size)
        if f.is_int:
            return int  # enum getters return pybind11 enums
        return {"text": str,  # imcpy's str, lossy for non-ASCII bytes (see the module docstring)
                "bytes": bytes.hex,
                "inline": self.inline_out,
                "list": lambda items: [self.inline_out(m) for m in items]}[f.kind]


def float_in(value, width: int):
    """A Python float for a float string (via its bits at ``width``); any other value as is, for imcpy to judge."""
    if isinstance(value, str):
        as_float, as_bits = FLOAT[width]
        return as_float.unpack(as_bits.pack(float_bits(value, width)))[0]
    return value


def check_suite(suite) -> None:
    if suite != SUITE:
        raise Unsupported(f"imcpy implements only the {SUITE!r} suite, not {suite!r}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--definitions", type=Path, default=DEFINITIONS)
    args = parser.parse_args(argv)
    return serve(lambda: ImcpyShim(json.loads(args.definitions.read_text(encoding="utf-8"))))


if __name__ == "__main__":
    sys.exit(main())
