"""pyimclsts behind the subprocess adapter protocol; standard library and pyimclsts only.

Usage: ``python adapters/pyimclsts_shim.py [--imc-xml PATH] [--cache DIR] [--definitions PATH]``.
Reads one JSON request per line on stdin and writes one JSON answer per line on stdout (protocol:
``imc_conformance.sessions.subprocess``): ``{"id", "ok": true, ...}``, a refusal ``{"id", "ok": false,
"error", "rule"?}``, an absent capability ``{"id", "ok": false, "unsupported": true, "error"}``, and
``{"id", "ok": false, "internal": true, "error"}`` when the shim itself fails (an adapter error).

pyimclsts works from classes generated out of an IMC.xml by ``python -m pyimclsts.extract`` (run in a
folder holding ``IMC.xml``; it writes ``pyimc_generated/`` there). The shim generates them once into
``<cache>/pyimclsts-<version>`` (a temporary folder renamed into place) from ``--imc-xml`` or ``$IMC_XML``;
``--cache`` defaults to ``$IMC_CONFORMANCE_CACHE`` or ``~/.cache/imc-conformance``. ``pyimclsts.network``
loads that package from ``os.getcwd()`` at import, so the shim imports it from inside the folder.

It behaves as the pyimclsts library adapter does, quirks included, but shares no code with it: field
names and types come from ``vectors/imc/definitions.json`` (or ``--definitions``), fields are assigned
through pyimclsts's attributes (which check types, enums and ranges) and read from its ``_<field>``
slots (the attributes deep-copy message values, which fails); ``{"hex"}`` plaintext travels as
surrogate-escaped ASCII as pyimclsts does; decode errors naming a CRC or the sync are ``crc``/``sync``,
``struct`` range errors on pack are ``value-out-of-type`` where a value given is out of its type, and name no
rule where a length or count overflows. Floats are answered at their width, with
``nan``/``inf``/``-inf``, ``-0.0`` and NaN payloads kept.
"""

from __future__ import annotations

import argparse
import importlib.metadata
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from shim_protocol import FLOAT, Refused, Unsupported, float_bits, float_value, serve

DEFINITIONS = Path(__file__).resolve().parent.parent / "vectors" / "imc" / "definitions.json"
PACKAGE = "pyimc_generated"  # fixed by pyimclsts.extract and pyimclsts.network
VERSION = importlib.metadata.version("pyimclsts")
MARKER = "generation.json"
WIDTH = {"fp32_t": 4, "fp64_t": 8}





# ---------------------------------------------------------------- generated classes

def generated_dir(cache: Path, imc_xml: str | None) -> Path:
    """The folder holding the generated package, generating it once (safe against concurrent shims)."""
    folder = cache / f"pyimclsts-{VERSION}"
    if not (folder / MARKER).exists():
        if not imc_xml:
            sys.exit(f"pyimclsts shim: no generated classes in {folder}; pass --imc-xml or set IMC_XML")
        generate(folder, Path(imc_xml))
    return folder


def generate(folder: Path, xml: Path) -> None:
    folder.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=folder.name + ".", suffix=".tmp", dir=folder.parent))
    try:
        shutil.copyfile(xml, tmp / "IMC.xml")
        done = subprocess.run([sys.executable, "-m", "pyimclsts.extract"], cwd=tmp, capture_output=True,
                              text=True, timeout=300)
        if done.returncode != 0 or not (tmp / PACKAGE / "__init__.py").exists():
            sys.exit(f"pyimclsts shim: pyimclsts.extract failed ({done.returncode}): {done.stderr.strip()[-500:]}")
        (tmp / MARKER).write_text(json.dumps({"pyimclsts": VERSION, "imc_xml": xml.name}), encoding="utf-8")
        try:
            os.rename(tmp, folder)  # atomic: the folder appears complete or not at all
        except OSError:
            if not (folder / MARKER).exists():
                raise  # else another shim generated it first
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def import_network(folder: Path):
    """``pyimclsts.network``, which loads ``pyimc_generated`` from the working directory at import."""
    cwd = os.getcwd()
    os.chdir(folder)
    try:
        import pyimclsts.network as network
    finally:
        os.chdir(cwd)
    return network


# ---------------------------------------------------------------- decoded-form values

def float_in(value, width: int):
    """A Python float for a float string (via its bits at ``width``); anything else is pyimclsts's to judge."""
    if not isinstance(value, str):
        return value
    try:
        bits = float_bits(value, width)
    except ValueError:
        return value
    as_float, as_bits = FLOAT[width]
    return as_float.unpack(as_bits.pack(bits))[0]


def float_out(width: int):
    return lambda x: float_value(x, width)


def text_in(value):
    if isinstance(value, dict) and set(value) == {"hex"} and isinstance(value["hex"], str):
        try:
            return bytes.fromhex(value["hex"]).decode("ascii", "surrogateescape")
        except ValueError:
            pass
    return value


def text_out(value: str):
    raw = value.encode("ascii", "surrogateescape")
    return raw.decode("ascii") if raw.isascii() else {"hex": raw.hex()}


def raw_in(value):
    if isinstance(value, str):
        try:
            return bytes.fromhex(value)
        except ValueError:
            pass
    return value


def int_bounds(ftype: str):
    """(min, max) of an integer type other than uint64, else None."""
    match = re.fullmatch(r"(u?)int(8|16|32|64)_t", ftype)
    if match is None or ftype == "uint64_t":
        return None
    bits = int(match[2])
    return (0, (1 << bits) - 1) if match[1] else (-(1 << (bits - 1)), (1 << (bits - 1)) - 1)


class Field:
    """One field: decoded-form name, pyimclsts attribute, wire type, converters both ways."""

    __slots__ = ("name", "attr", "slot", "type", "bounds", "into", "out")

    def __init__(self, name: str, attr: str, ftype: str, into, out):
        self.name, self.attr, self.slot, self.type = name, attr, "_" + attr, ftype
        self.bounds, self.into, self.out = int_bounds(ftype), into, out

    def rule_for(self, value) -> str | None:
        """``value-out-of-type`` for an integer that does not fit this field's integer type."""
        if self.bounds is None or isinstance(value, bool) or not isinstance(value, int):
            return None
        return None if self.bounds[0] <= value <= self.bounds[1] else "value-out-of-type"


class Message:
    __slots__ = ("abbrev", "cls", "fields", "by_name")

    def __init__(self, abbrev: str, cls, fields: list[Field]):
        self.abbrev, self.cls, self.fields = abbrev, cls, fields
        self.by_name = {f.name: f for f in fields}


# ---------------------------------------------------------------- the shim

class PyimclstsShim:
    """hello / encode / decode over pyimclsts's generated classes and ``unpack``, in the decoded form."""

    def __init__(self, network, definitions: dict):
        self.unpack, self.messages = network.unpack, network._pg.messages
        self.header_data = network._pg._base.header_data
        self.header_defaults = {k: v for k, v in definitions["frame"]["header_defaults"].items() if k != "source"}
        self.defs = {m["abbrev"]: m for m in definitions["messages"]}
        self.classes = {abbrev: getattr(self.messages, abbrev) for abbrev in self.messages._message_ids.values()}
        self.converters = {abbrev: self.message(abbrev) for abbrev in self.classes}

    def hello(self) -> dict:
        return {"implementation": f"pyimclsts {VERSION}", "suites": ["imc"], "byte_orders": ["be", "le"],
                "errata": "pyimclsts"}

    def encode(self, suite, message, byte_order) -> bytes:
        check_suite(suite)
        if byte_order not in ("be", "le"):
            raise Unsupported(f"byte order {byte_order!r}")
        abbrev = message.get("abbrev")
        obj = self.build(abbrev, message.get("fields", {}), str(abbrev))
        header = dict(self.header_defaults, **message.get("header", {}))
        obj._header = self.header_data(None, None, None, float_in(header["timestamp"], 8), header["src"],
                                       header["src_ent"], header["dst"], header["dst_ent"])
        try:
            return obj.pack(is_big_endian=byte_order == "be")
        except Exception as exc:  # struct's range check: value-out-of-type for a value given out of its type, no rule
            # for a length or count over 65535
            raise Refused(f"{abbrev}: pack: {type(exc).__name__}: {exc}",
                          "value-out-of-type" if self.holds_out_of_type(message) else None) from exc

    def holds_out_of_type(self, message: dict) -> bool:
        """Whether an integer of the header or of any field, inline messages included, does not fit its type."""
        header = message.get("header", {})
        tops = {"src": 0xFFFF, "src_ent": 0xFF, "dst": 0xFFFF, "dst_ent": 0xFF}
        if any(isinstance(header.get(name), int) and not 0 <= header[name] <= top for name, top in tops.items()):
            return True
        pending = [message]
        while pending:
            current = pending.pop()
            conv = self.converters.get(current.get("abbrev")) if isinstance(current, dict) else None
            if conv is None:
                continue
            for name, value in current.get("fields", {}).items():
                field = conv.by_name.get(name)
                if field is not None and field.rule_for(value):
                    return True
                pending += [v for v in (value if isinstance(value, list) else [value]) if isinstance(v, dict)]
        return False

    def build(self, abbrev, fields: dict, where: str):
        """A pyimclsts message object with ``fields`` assigned through its attributes."""
        conv = self.converters.get(abbrev) if isinstance(abbrev, str) else None
        if conv is None:
            raise Refused(f"{where}: pyimclsts has no message {abbrev!r}")
        obj = conv.cls()
        for name, value in fields.items():
            field = conv.by_name.get(name)
            if field is None:
                raise Refused(f"{where}: pyimclsts's {abbrev} has no field {name!r}")
            if field.type == "message" and value is None:
                continue  # a null inline message is the field as constructed
            value = field.into(value, f"{where}.{name}")
            try:
                setattr(obj, field.attr, value)
            except Exception as exc:
                raise Refused(f"{where}.{name}: {type(exc).__name__}: {exc}", field.rule_for(value)) from exc
        return obj

    def inline_in(self, value, where: str):
        if isinstance(value, dict):
            return self.build(value.get("abbrev"), value.get("fields", {}), f"{where}.{value.get('abbrev')}")
        return value

    def list_in(self, value, where: str):
        if isinstance(value, list):
            return [self.inline_in(v, f"{where}[{i}]") for i, v in enumerate(value)]
        return value

    def decode(self, suite, frame: bytes) -> dict:
        check_suite(suite)
        try:
            obj = self.unpack(frame)
        except Exception as exc:
            text = f"{type(exc).__name__}: {exc}"
            rule = "crc" if re.search(r"\bcrc", text, re.I) else "sync" if re.search(r"\bsync", text, re.I) else None
            raise Refused(f"pyimclsts.network.unpack: {text}", rule) from exc
        h = obj._header
        header = {"timestamp": float_out(8)(h.timestamp), "src": h.src, "src_ent": h.src_ent,
                  "dst": h.dst, "dst_ent": h.dst_ent}
        if type(obj) is self.messages.Unknown:
            return {"abbrev": obj.Attributes.abbrev, "header": header, "fields": {}}
        conv = self.converters[obj.Attributes.abbrev]
        return {"abbrev": conv.abbrev, "header": header, "fields": fields_out(conv, obj)}

    def inline_out(self, obj):
        if obj is None:
            return None
        conv = self.converters[obj.Attributes.abbrev]
        return {"abbrev": conv.abbrev, "fields": fields_out(conv, obj)}

    def list_out(self, objs):
        return [self.inline_out(o) for o in objs]

    # ------------------------------------------------------------ converters

    def message(self, abbrev: str) -> Message:
        """The converters of one pyimclsts class, fields named as the definitions name them if they have it."""
        cls = self.classes[abbrev]
        attrs = cls.Attributes.fields
        py_type = {a: getattr(cls, a)._field_def["type"] for a in attrs}
        mdef = self.defs.get(abbrev)
        if mdef is None:
            return Message(abbrev, cls, [self.field(a, a, py_type[a]) for a in attrs])
        fields = []
        for fdef in mdef["fields"]:
            name, ftype = fdef["abbrev"], fdef["type"]
            match = [a for a in attrs if a == name] or [a for a in attrs if a.lower() == name.lower()]
            if len(match) != 1 or py_type[match[0]] != ftype:
                raise RuntimeError(f"pyimclsts's {abbrev} does not match the definitions' {name} ({ftype}): "
                                   f"attributes {attrs}, types {py_type}")
            fields.append(self.field(name, match[0], ftype))
        return Message(abbrev, cls, fields)

    def field(self, name: str, attr: str, ftype: str) -> Field:
        if ftype in WIDTH:
            width = WIDTH[ftype]
            return Field(name, attr, ftype, lambda v, _w: float_in(v, width), float_out(width))
        into, out = {
            "plaintext": (lambda v, _w: text_in(v), text_out),
            "rawdata": (lambda v, _w: raw_in(v), bytes.hex),
            "message": (self.inline_in, self.inline_out),
            "message-list": (self.list_in, self.list_out),
        }.get(ftype, (lambda v, _w: v, int))
        return Field(name, attr, ftype, into, out)


def fields_out(conv: Message, obj) -> dict:
    return {f.name: f.out(getattr(obj, f.slot)) for f in conv.fields}


def check_suite(suite) -> None:
    if suite != "imc":
        raise Unsupported(f"suite {suite!r}")


def default_cache() -> Path:
    return Path(os.environ.get("IMC_CONFORMANCE_CACHE") or Path.home() / ".cache" / "imc-conformance")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--imc-xml", default=os.environ.get("IMC_XML"))
    parser.add_argument("--cache", type=Path, default=default_cache())
    parser.add_argument("--definitions", type=Path, default=DEFINITIONS)
    args = parser.parse_args(argv)
    return serve(lambda: PyimclstsShim(import_network(generated_dir(args.cache, args.imc_xml)),
                                       json.loads(args.definitions.read_text(encoding="utf-8"))))


if __name__ == "__main__":
    sys.exit(main())
