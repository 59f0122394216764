"""Library adapter for pyimclsts 0.1.2.1, the pure-Python IMC codec from LSTS.

pyimclsts works from message classes generated out of an IMC.xml: ``python -m pyimclsts.extract``,
run in a folder that holds ``IMC.xml``, writes the package ``pyimc_generated/`` (``messages.py``,
``_base.py``, ``enumerations.py``, ``bitfields.py``, ``categories/``) into that folder. The adapter
runs it once (a subprocess, in a temporary folder renamed into place) into
``cache_dir()/pyimclsts-<version>`` from the suite's real IMC.xml. ``pyimclsts.network`` (home of
``unpack``) loads the generated package at import time from ``os.getcwd() + "/pyimc_generated"`` and
registers it as ``sys.modules["pyimc_generated"]``; the adapter imports it with an ``os`` whose
``getcwd`` names the cache folder, seen by that module alone, so the caller's working directory is
neither used nor changed. Nothing happens at import of this module: all of it on the first ``adapter()``.

Encoding builds an empty message object and assigns every field through pyimclsts's attributes (where
it checks types, enum membership and min/max), sets the header the way ``unpack`` does (``_header``),
and calls ``pack(is_big_endian=...)``. Decoding calls ``pyimclsts.network.unpack(frame)``.

Quirks observed (each pinned in tests/test_pyimclsts_adapter.py):

- ``unpack`` checks neither the CRC nor the sync number, nor the header's size field: a frame with a
  flipped CRC decodes; a frame whose sync is neither ``fe54`` nor ``54fe`` is read as little-endian;
  bytes past the fields are ignored; a plaintext/rawdata length running past the frame is cut short.
- An unknown message id decodes as an ``Unknown`` object (payload kept as ``contents``; its
  ``Attributes.id`` is the builtin ``id`` function, a slip of the generator); reported as
  ``{"abbrev": "Unknown", ...}`` with no fields, an acceptance. An unknown id inside a message or a list
  raises ``KeyError`` (refused).
- HistoricData's ``data`` carries ``message-type="RemoteData"`` (a message group) and pyimclsts compares
  each element's abbrev with it, so a non-empty HistoricData can be neither assigned (encode) nor
  decoded: ``ValueError: Cannot have <class ...RemoteCommand'> in the list of attribute 'data'``.
- Plaintext is ASCII with ``surrogateescape``: a ``str`` with a non-ASCII character fails in ``pack``
  (``UnicodeEncodeError``); non-ASCII bytes decode to lone surrogates, which give back the exact bytes.
  The adapter hands ``{"hex"}`` plaintext to pyimclsts in that same surrogate-escaped form.
- Assignment enforces enum membership (``ValueError: 7 is not a valid LblConfig.OP``) and the XML's
  min/max, on encode and, since ``unpack`` assigns too, on decode. Bitfields are ``IntFlag`` and take any
  value, a negative one silently becoming the set of known flags (-1 -> 3 for AnnounceService).
  Integer ranges are checked only by ``struct`` in ``pack``: the adapter names that refusal ``value-out-of-type``
  where a value given is out of its type, and no rule where it is a length or count over 65535 (the same error);
  ``bool`` passes as ``int``.
- A message-list element cannot be null: assigning ``None`` in a list raises ``ValueError``; decoding a
  null id (65535) in a list raises ``KeyError``. A null inline message is the unassigned field.
- An inline message field left out of ``fields`` packs as null (no missing-field refusal).
- Reading a message or message-list field through its public attribute deep-copies it, which fails
  (``AttributeError: ... 'Attributes' is read-only``); the adapter reads the ``_<field>`` slots.
- Floats go through Python doubles: a signalling fp32 NaN comes back quieted (CPython's conversion).
"""

from __future__ import annotations

import builtins
import importlib.metadata
import importlib.util
import json
import os
import re
import shutil
import struct
import subprocess
import sys
import tempfile
import threading
import time
import types
from pathlib import Path

from imc_conformance.adapter_api import Rejected, Unsupported
from imc_conformance.suites.imc.definitions import Definitions, MessageDef, load_definitions
from imc_conformance.suites.imc.imc_xml import cache_dir, fetch_imc_xml
from imc_conformance.kinds.vector.floats import float_from_bits, float_to_bits
from imc_conformance.suites.imc.values import text_value

PACKAGE = "pyimc_generated"  # fixed by pyimclsts.extract (_target_folder) and pyimclsts.network (_module_name)
VERSION = importlib.metadata.version("pyimclsts")
_MARKER = "generation.json"
_HEADER_TOPS = {"src": 0xFFFF, "src_ent": 0xFF, "dst": 0xFFFF, "dst_ent": 0xFF}  # the header's integers
_FLOATS = {"fp32_t": (4, struct.Struct("<f"), struct.Struct("<I")),
           "fp64_t": (8, struct.Struct("<d"), struct.Struct("<Q"))}


# ---------------------------------------------------------------- generation and import

def generated_dir(timeout: float = 300) -> Path:
    """The cache folder holding the generated package, generating it once (safe against races)."""
    folder = cache_dir() / f"pyimclsts-{VERSION}"
    if not (folder / _MARKER).exists():
        _generate(folder, timeout)
    return folder


def _generate(folder: Path, timeout: float) -> None:
    xml = fetch_imc_xml()
    tmp = Path(tempfile.mkdtemp(prefix=folder.name + ".", suffix=".tmp", dir=folder.parent))
    try:
        shutil.copyfile(xml, tmp / "IMC.xml")
        start = time.perf_counter()
        done = subprocess.run([sys.executable, "-m", "pyimclsts.extract"], cwd=tmp,
                              capture_output=True, text=True, timeout=timeout)
        seconds = time.perf_counter() - start
        if done.returncode != 0 or not (tmp / PACKAGE / "__init__.py").exists():
            raise RuntimeError(f"pyimclsts.extract failed ({done.returncode}): {done.stderr.strip()[-500:]}")
        info = {"pyimclsts": VERSION, "imc_xml": xml.name, "seconds": round(seconds, 3)}
        (tmp / _MARKER).write_text(json.dumps(info), encoding="utf-8")
        try:
            os.rename(tmp, folder)  # atomic: the folder appears complete or not at all
        except OSError:
            if not (folder / _MARKER).exists():
                raise
            # another process generated it first; use theirs
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


class _OsWithCwd(types.ModuleType):
    """``os`` as seen by pyimclsts.network while it loads: ``getcwd()`` names the generated folder."""

    def __init__(self, cwd: Path):
        super().__init__("os")
        self._cwd = str(cwd)

    def getcwd(self) -> str:
        return self._cwd

    def __getattr__(self, name):
        return getattr(os, name)


def _import_network(folder: Path):
    """``pyimclsts.network``, loading the generated package found in ``folder``.

    Its ``import os`` gets ``_OsWithCwd`` (kept as its ``_os``, read only at import); no other module
    and no global state sees it.
    """
    network = sys.modules.get("pyimclsts.network")
    if network is None:
        spec = importlib.util.find_spec("pyimclsts.network")
        network = importlib.util.module_from_spec(spec)
        real_import = builtins.__import__

        def import_(name, globals=None, locals=None, fromlist=(), level=0):
            module = real_import(name, globals, locals, fromlist, level)
            return _OsWithCwd(folder) if name == "os" and level == 0 else module

        network.__builtins__ = dict(vars(builtins), __import__=import_)  # this module's imports only
        sys.modules[spec.name] = network
        try:
            spec.loader.exec_module(network)
        except BaseException:
            sys.modules.pop(spec.name, None)
            raise
        sys.modules["pyimclsts"].network = network
    loaded = Path(network._pg.__file__).resolve()
    if loaded != (folder / PACKAGE / "__init__.py").resolve():
        raise RuntimeError(f"pyimclsts.network was already imported with the classes of {loaded}")
    return network


# ---------------------------------------------------------------- value conversions

def _float_in(width: int, value):
    """A Python float for a canonical float string; anything else is pyimclsts's to judge."""
    if isinstance(value, str):
        try:
            bits = float_to_bits(value, width)
        except ValueError:
            return value
        _, as_float, as_bits = _FLOATS["fp32_t" if width == 4 else "fp64_t"]
        return as_float.unpack(as_bits.pack(bits))[0]
    return value


def _text_in(value):
    if isinstance(value, dict) and set(value) == {"hex"} and isinstance(value["hex"], str):
        try:
            return bytes.fromhex(value["hex"]).decode("ascii", "surrogateescape")
        except ValueError:
            pass
    return value


def _raw_in(value):
    if isinstance(value, str):
        try:
            return bytes.fromhex(value)
        except ValueError:
            pass
    return value


def _float_out(ftype: str):
    width, as_float, as_bits = _FLOATS[ftype]
    return lambda v: float_from_bits(as_bits.unpack(as_float.pack(v))[0], width)


_timestamp_out = _float_out("fp64_t")


def _text_out(value: str):
    return text_value(value.encode("ascii", "surrogateescape"))


def _int_bounds(ftype: str):
    if ftype not in ("int8_t", "uint8_t", "int16_t", "uint16_t", "int32_t", "uint32_t", "int64_t"):
        return None
    bits = int(ftype.lstrip("u")[3:-2])
    return (0, (1 << bits) - 1) if ftype.startswith("u") else (-(1 << (bits - 1)), (1 << (bits - 1)) - 1)


class _Field:
    """One field: its decoded-form name, pyimclsts attribute, and converters in both directions."""

    __slots__ = ("name", "attr", "slot", "type", "bounds", "into", "out")

    def __init__(self, name: str, attr: str, ftype: str, into, out):
        self.name, self.attr, self.slot, self.type = name, attr, "_" + attr, ftype
        self.bounds, self.into, self.out = _int_bounds(ftype), into, out

    def rule_for(self, value) -> str | None:
        """``value-out-of-type`` if ``value`` is an integer that does not fit this field's type."""
        if self.bounds is None or isinstance(value, bool) or not isinstance(value, int):
            return None
        return None if self.bounds[0] <= value <= self.bounds[1] else "value-out-of-type"


class _Message:
    __slots__ = ("abbrev", "cls", "fields", "by_name")

    def __init__(self, abbrev: str, cls, fields: list[_Field]):
        self.abbrev, self.cls, self.fields = abbrev, cls, fields
        self.by_name = {f.name: f for f in fields}


# ---------------------------------------------------------------- the adapter

class PyimclstsAdapter:
    """Drives pyimclsts's generated classes and ``unpack`` in the corpus's decoded form."""

    def __init__(self, network, defs: Definitions, generation: dict):
        self._unpack = network.unpack
        self._messages = network._pg.messages
        self._header_data = network._pg._base.header_data
        self._defs, self.generation = defs, generation
        self._classes = {abbrev: getattr(self._messages, abbrev) for abbrev in self._messages._message_ids.values()}
        self._converters: dict[str, _Message] = {}

    def hello(self) -> dict:
        return {"implementation": f"pyimclsts {VERSION}", "suites": ["imc"], "byte_orders": ["be", "le"],
                "errata": "pyimclsts"}

    # -------------------------------------------------------- encoding

    def encode(self, suite: str, message: dict, byte_order: str) -> bytes:
        _check_suite(suite)
        if byte_order not in ("be", "le"):
            raise Unsupported(f"byte order {byte_order!r}")
        abbrev = message.get("abbrev")
        obj = self._build(abbrev, message.get("fields", {}), str(abbrev))
        header = dict(self._defs.header_defaults, **message.get("header", {}))
        obj._header = self._header_data(None, None, None, _float_in(8, header["timestamp"]), header["src"],
                                        header["src_ent"], header["dst"], header["dst_ent"])
        try:
            return obj.pack(is_big_endian=byte_order == "be")
        except Exception as exc:  # struct's range check is pyimclsts's only one: it names value-out-of-type where a
            # value given is out of its type, and no rule where a length or count overflows (payload-overflow is no
            # check of pyimclsts's own)
            raise Rejected(f"{abbrev}: pack: {type(exc).__name__}: {exc}",
                           "value-out-of-type" if self._out_of_type(message) else None) from exc

    def _out_of_type(self, message: dict) -> bool:
        """Whether a header value or a field value (inline messages included) is an integer its type cannot hold."""
        header = message.get("header", {})
        if any(isinstance(header.get(k), int) and not 0 <= header[k] <= top for k, top in _HEADER_TOPS.items()):
            return True
        stack = [message]
        while stack:
            m = stack.pop()
            conv = self._converter(m.get("abbrev")) if isinstance(m, dict) else None
            for name, value in (m.get("fields", {}).items() if conv is not None else ()):
                field = conv.by_name.get(name)
                if field is None:
                    continue
                if field.rule_for(value):
                    return True
                stack += [v for v in (value if isinstance(value, list) else [value]) if isinstance(v, dict)]
        return False

    def _build(self, abbrev, fields: dict, where: str):
        """A pyimclsts message object with ``fields`` assigned through its attributes."""
        conv = self._converter(abbrev)
        if conv is None:
            raise Rejected(f"{where}: pyimclsts has no message {abbrev!r}")
        obj = conv.cls()
        for name, value in fields.items():
            field = conv.by_name.get(name)
            if field is None:
                raise Rejected(f"{where}: pyimclsts's {abbrev} has no field {name!r}")
            if field.type == "message" and value is None:
                continue  # null inline message: the field as constructed (None)
            value = field.into(value, f"{where}.{name}")
            try:
                setattr(obj, field.attr, value)
            except Exception as exc:
                raise Rejected(f"{where}.{name}: {type(exc).__name__}: {exc}", field.rule_for(value)) from exc
        return obj

    def _inline_in(self, value, where: str):
        if isinstance(value, dict):
            return self._build(value.get("abbrev"), value.get("fields", {}), f"{where}.{value.get('abbrev')}")
        return value

    def _list_in(self, value, where: str):
        if isinstance(value, list):
            return [self._inline_in(v, f"{where}[{i}]") for i, v in enumerate(value)]
        return value

    # -------------------------------------------------------- decoding

    def decode(self, suite: str, frame: bytes) -> dict:
        _check_suite(suite)
        try:
            obj = self._unpack(bytes(frame))
        except Exception as exc:
            text = f"{type(exc).__name__}: {exc}"
            rule = "crc" if re.search(r"\bcrc", text, re.I) else "sync" if re.search(r"\bsync", text, re.I) else None
            raise Rejected(f"pyimclsts.network.unpack: {text}", rule) from exc
        h = obj._header
        header = {"timestamp": _timestamp_out(h.timestamp), "src": h.src, "src_ent": h.src_ent,
                  "dst": h.dst, "dst_ent": h.dst_ent}
        if type(obj) is self._messages.Unknown:
            return {"abbrev": obj.Attributes.abbrev, "header": header, "fields": {}}
        conv = self._converter(obj.Attributes.abbrev)
        return {"abbrev": conv.abbrev, "header": header, "fields": self._fields_out(conv, obj)}

    @staticmethod
    def _fields_out(conv: _Message, obj) -> dict:
        # the slots, not the attributes: those deep-copy message values, which fails
        return {f.name: f.out(getattr(obj, f.slot)) for f in conv.fields}

    def _inline_out(self, obj):
        if obj is None:
            return None
        conv = self._converter(obj.Attributes.abbrev)
        return {"abbrev": conv.abbrev, "fields": self._fields_out(conv, obj)}

    def _list_out(self, objs):
        return [self._inline_out(o) for o in objs]

    # -------------------------------------------------------- converters

    def _converter(self, abbrev) -> _Message | None:
        """The field converters of a message (cached); None if pyimclsts has no such class."""
        conv = self._converters.get(abbrev) if isinstance(abbrev, str) else None
        if conv is None:
            cls = self._classes.get(abbrev) if isinstance(abbrev, str) else None
            if cls is None:
                return None
            mdef = self._defs.by_abbrev.get(abbrev)
            conv = self._converters[abbrev] = _Message(abbrev, cls, self._fields_of(cls, mdef))
        return conv

    def _fields_of(self, cls, mdef: MessageDef | None) -> list[_Field]:
        """Fields named as the definitions name them, or as pyimclsts does for a message they lack."""
        attrs = cls.Attributes.fields
        py_type = {a: getattr(cls, a)._field_def["type"] for a in attrs}
        if mdef is None:
            return [self._field(a, a, py_type[a]) for a in attrs]
        fields = []
        for fdef in mdef.fields:
            match = [a for a in attrs if a == fdef.abbrev] or [a for a in attrs if a.lower() == fdef.abbrev.lower()]
            if len(match) != 1 or py_type[match[0]] != fdef.type:
                raise RuntimeError(f"pyimclsts's {mdef.abbrev} does not match the definitions' {fdef.abbrev} "
                                   f"({fdef.type}): attributes {attrs}, types {py_type}")
            fields.append(self._field(fdef.abbrev, match[0], fdef.type))
        return fields

    def _field(self, name: str, attr: str, ftype: str) -> _Field:
        if ftype in _FLOATS:
            width = _FLOATS[ftype][0]
            return _Field(name, attr, ftype, lambda v, _w: _float_in(width, v), _float_out(ftype))
        if ftype == "plaintext":
            return _Field(name, attr, ftype, lambda v, _w: _text_in(v), _text_out)
        if ftype == "rawdata":
            return _Field(name, attr, ftype, lambda v, _w: _raw_in(v), bytes.hex)
        if ftype == "message":
            return _Field(name, attr, ftype, self._inline_in, self._inline_out)
        if ftype == "message-list":
            return _Field(name, attr, ftype, self._list_in, self._list_out)
        return _Field(name, attr, ftype, lambda v, _w: v, int)


def _check_suite(suite: str) -> None:
    if suite != "imc":
        raise Unsupported(f"suite {suite!r}")


_lock = threading.Lock()
_instance: PyimclstsAdapter | None = None


def adapter() -> PyimclstsAdapter:
    """The adapter; the first call generates (once per cache) and imports pyimclsts's classes."""
    global _instance
    with _lock:
        if _instance is None:
            folder = generated_dir()
            info = json.loads((folder / _MARKER).read_text(encoding="utf-8"))  # includes the extractor's seconds
            _instance = PyimclstsAdapter(_import_network(folder), load_definitions(), info)
        return _instance
