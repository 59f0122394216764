"""Library adapter for genpy, the canonical ROS 1 Python code, from Debian's packages (never a system install).

On first use ``apt-get download`` fetches python3-genpy, python3-genmsg, python3-std-msgs and ros-std-msgs
into the cache folder and ``dpkg -x`` unpacks them there (the PyPI package named genpy is unrelated).
Classes are then generated with genpy's own ``genmsg_py.py`` and ``gensrv_py.py`` from .msg text: the
suite's edition (``--adapter-arg edition=9.0.0``) or a team's package (``--adapter-arg msgs=DIR``, its
``msg/*.msg`` and ``srv/*.srv``), cached by the text's hash. A service half of an edition that lacks the
other half is generated as a message of the same name (same MD5 and type name, no service MD5).
Messages move between the decoded form and genpy objects by genpy's own slots and slot types.
"""

from __future__ import annotations

import importlib
import io
import logging
import struct
import sys
from pathlib import Path

import yaml  # noqa: F401  genpy (and its generators, run with this interpreter) need it: the ros extra's pyyaml
from imc_conformance.adapter_api import Rejected, Unsupported
from imc_conformance.native import debian_packages, run
from imc_conformance.kinds.vector.floats import float_from_bits, float_to_bits
from imc_conformance.suites.ros_acomms.codec import int_form, int_value
from imc_conformance.suites.ros_acomms.package_files import generated_package, source_files

SUITE = "ros_acomms"
PACKAGE = "ros_acomms_msgs"
DEBS = ("python3-genpy", "python3-genmsg", "python3-std-msgs", "ros-std-msgs")
DIST = Path("usr/lib/python3/dist-packages")
FLOATS = {"float32": "f", "float64": "d"}
INTS = {"int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64", "byte", "char"}


def debian_genpy() -> tuple[Path, dict[str, str]]:
    """The unpacked Debian packages (downloaded once into the cache) and their versions."""
    return debian_packages("debian-genpy", DEBS)


def generate(root: Path, versions: dict, files: dict[str, str]) -> Path:
    """The folder holding the generated ``ros_acomms_msgs`` package (generated once per text)."""

    def make(src: Path, gen: Path, env: dict, includes: list[str]) -> None:
        for kind, script in (("msg", "genmsg_py.py"), ("srv", "gensrv_py.py")):
            inputs = sorted((src / kind).glob(f"*.{kind}"))
            if inputs:
                tool, out = root / "usr/lib/genpy" / script, gen / PACKAGE / kind
                run([sys.executable, tool, "-p", PACKAGE, "-o", out, *includes, *inputs], f"genpy's {script}", env=env)
                run([sys.executable, tool, "--initpy", "-o", out], f"genpy's {script} --initpy", env=env)
        (gen / PACKAGE / "__init__.py").write_text("", encoding="utf-8")

    return generated_package("genpy", PACKAGE, root, versions, files, make)


class GenpyAdapter:
    def __init__(self, edition: str | None = None, msgs: str | None = None):
        if edition is not None and msgs is not None:
            raise ValueError("give edition or msgs, not both")
        root, self.versions = debian_genpy()
        gen = generate(root, self.versions, source_files(edition, msgs))
        for path in (str(root / DIST), str(gen)):
            if path not in sys.path:
                sys.path.insert(0, path)
        for name in [n for n in sys.modules if n == PACKAGE or n.startswith(PACKAGE + ".")]:
            del sys.modules[name]  # another variant of the package may be loaded already
        sys.path.remove(str(gen))
        sys.path.insert(0, str(gen))
        self.genpy = importlib.import_module("genpy")
        self.modules = [importlib.import_module(f"{PACKAGE}.{kind}") for kind in ("msg", "srv")
                        if (gen / PACKAGE / kind / "__init__.py").exists()]
        logging.getLogger("rosout").addHandler(logging.NullHandler())  # genpy logs replaced characters there
        logging.getLogger("rosout").propagate = False
        self.source = f"{msgs} .msg files" if msgs else f"the suite's {edition or 'seed'} edition"

    def hello(self) -> dict:
        return {"implementation": f"genpy {self.versions.get('python3-genpy', '?')} (Debian; classes from {self.source})",
                "suites": [SUITE], "encodings": ["ros1"], "errata": "genpy"}

    def _class(self, full, what="type"):
        package, _, name = str(full).partition("/")
        if package == "std_msgs":
            return getattr(importlib.import_module("std_msgs.msg"), name)
        for module in self.modules if package == PACKAGE else ():
            cls = getattr(module, name, None)
            if isinstance(cls, type):
                return cls
        raise Rejected(f"genpy has no {what} {full!r}", rule="unknown-type")

    # -------------------------------------------------------- encoding

    def encode(self, suite: str, message: dict, encoding: str) -> bytes:
        _check(suite, encoding)
        if not isinstance(message, dict):
            raise Rejected("a message must be an object", rule="value-type")
        obj = self._build(self._class(message.get("type")), message.get("fields"))
        buffer = io.BytesIO()
        try:
            obj.serialize(buffer)
        except self.genpy.SerializationError as exc:
            raise Rejected(str(exc), rule=_serialization_rule(str(exc))) from exc
        except OverflowError as exc:
            raise Rejected(str(exc), rule="value-out-of-type") from exc
        except (struct.error, TypeError, ValueError, AttributeError) as exc:
            raise Rejected(f"{type(exc).__name__}: {exc}", rule="value-type") from exc
        return buffer.getvalue()

    def _build(self, cls, fields):
        if not isinstance(fields, dict):
            raise Rejected(f"{cls._type}: fields must be an object", rule="value-type")
        unknown = sorted(set(fields) - set(cls.__slots__))
        if unknown:
            raise Rejected(f"{cls._type} has no field {unknown[0]!r}", rule="unknown-field")
        values = {}
        for name, slot_type in zip(cls.__slots__, cls._slot_types):
            if name not in fields:
                raise Rejected(f"{cls._type}.{name} is missing", rule="missing-field")
            values[name] = self._to(slot_type, fields[name], f"{cls._type}.{name}")
        return cls(**values)

    def _to(self, slot_type: str, value, where: str):
        base, array = _split(slot_type)
        try:
            if array is not None:
                if base in ("uint8", "char"):
                    return bytes.fromhex(value)
                if not isinstance(value, list):
                    raise Rejected(f"{where}: an array must be a list", rule="value-type")
                return [self._to(base, v, f"{where}[]") for v in value]
            if base == "bool":
                if not isinstance(value, bool):
                    raise Rejected(f"{where}: {value!r} is not a boolean", rule="value-type")
                return value
            if base in FLOATS:
                width = 4 if base == "float32" else 8
                return struct.unpack("<" + FLOATS[base], float_to_bits(value, width).to_bytes(width, "little"))[0]
            if base in INTS:
                number = int_value(value)
                if number is None:
                    raise Rejected(f"{where}: {value!r} is not an integer", rule="value-type")
                return number
            if base == "string":
                if not isinstance(value, str):
                    raise Rejected(f"{where}: genpy strings are text; these bytes are not UTF-8", rule="value-type")
                return value
            if base in ("time", "duration"):
                kind = self.genpy.Time if base == "time" else self.genpy.Duration
                return kind(value["secs"], value["nsecs"])
            return self._build(self._class(base), value)
        except Rejected:
            raise
        except (ValueError, TypeError, KeyError) as exc:
            raise Rejected(f"{where}: {exc}", rule="value-type") from exc

    # -------------------------------------------------------- decoding

    def decode(self, suite: str, frame: bytes, type: str = "", encoding: str = "ros1") -> dict:
        _check(suite, encoding)
        cls = self._class(type)
        try:
            obj = cls().deserialize(bytes(frame))
        except self.genpy.DeserializationError as exc:
            raise Rejected(str(exc)) from exc
        except Exception as exc:  # what a corrupt frame makes generated code raise
            raise Rejected(f"{exc.__class__.__name__}: {exc}") from exc
        return {"type": type, "fields": self._fields(obj)}

    def _fields(self, obj) -> dict:
        return {name: self._from(slot_type, getattr(obj, name)) for name, slot_type in zip(obj.__slots__, obj._slot_types)}

    def _from(self, slot_type: str, value):
        base, array = _split(slot_type)
        if array is not None:
            if base in ("uint8", "char"):
                return bytes(value).hex()
            return [self._from(base, v) for v in value]
        if base == "bool":
            return bool(value)
        if base in FLOATS:
            width = 4 if base == "float32" else 8
            return float_from_bits(int.from_bytes(struct.pack("<" + FLOATS[base], value), "little"), width)
        if base in INTS:
            return int_form(int(value))
        if base == "string":
            return value
        if base in ("time", "duration"):
            return {"secs": int(value.secs), "nsecs": int(value.nsecs)}
        return self._fields(value)

    # -------------------------------------------------------- definitions

    def describe(self, suite: str, type: str = "") -> dict:
        _check(suite, "ros1")
        cls = self._class(type)
        out = {"md5": cls._md5sum, "definition": cls._full_text}
        for module in self.modules:  # a service half: its service's MD5 too
            service = getattr(module, str(type).partition("/")[2].removesuffix("Request").removesuffix("Response"), None)
            if service is not None and getattr(service, "_request_class", None) is not None:
                out["service_md5"] = service._md5sum
        return out


def _check(suite: str, encoding: str) -> None:
    if suite != SUITE:
        raise Unsupported(f"suite {suite!r}")
    if encoding != "ros1":
        raise Unsupported(f"encoding {encoding!r}")


def _split(slot_type: str) -> tuple[str, int | None]:
    """``'CST[]'`` -> ``('CST', -1)``; ``'bool[4]'`` -> ``('bool', 4)``; ``'int16'`` -> ``('int16', None)``."""
    if not slot_type.endswith("]"):
        return slot_type, None
    base, _, size = slot_type[:-1].partition("[")
    return base, int(size) if size else -1


def _serialization_rule(text: str) -> str | None:
    if "exceeds specified width" in text or "must be unsigned" in text:
        return "value-out-of-type"
    if "expected" in text and "items for packing" in text:
        return "fixed-array-length"
    return "value-type"
