"""Library adapter for rosbags (PyPI): ROS 1 serialization through a rosbags typestore.

The typestore (``Stores.ROS1_NOETIC``, whose std_msgs/Header has ``seq``) is built from .msg text: by
default the suite's own text of an edition (``--adapter-arg edition=9.0.0``), or a team's own package
(``--adapter-arg msgs=path/to/ros_acomms_msgs``, its ``msg/*.msg`` and ``srv/*.srv``), so that a team
checks *their* definitions. Messages move between the decoded form and rosbags objects by rosbags' own
field definitions, through converters built once per type (a function per field, each way): a field the
implementation's definition names differently shows as a difference.
Service halves are registered as ``<pkg>/msg/<Service>Request``/``Response`` (rosbags resolves relative
names against ``<pkg>/msg``). A type the typestore lacks is refused (``unknown-type``).
"""

from __future__ import annotations

import struct
from importlib.metadata import version
from math import isfinite
from pathlib import Path

import numpy as np
from rosbags.serde import SerdeError
from rosbags.typesys import Stores, get_typestore, get_types_from_msg
from rosbags.typesys.base import Nodetype

from imc_conformance.adapter_api import Rejected, Unsupported
from imc_conformance.kinds.vector.floats import float_from_bits, float_to_bits
from imc_conformance.suites.ros_acomms.codec import int_form, int_value
from imc_conformance.suites.ros_acomms.definitions import load_definitions
from imc_conformance.suites.ros_acomms.msgtext import msg_text
from imc_conformance.suites.ros_acomms.package_files import read_package

SUITE = "ros_acomms"
PACKAGE = "ros_acomms_msgs"
DTYPES = {"bool": np.bool_, "int8": np.int8, "uint8": np.uint8, "int16": np.int16, "uint16": np.uint16,
          "int32": np.int32, "uint32": np.uint32, "int64": np.int64, "uint64": np.uint64, "float32": np.float32,
          "float64": np.float64}
FLOATS = {"float32": 4, "float64": 8}
TIMES = ("builtin_interfaces/msg/Time", "builtin_interfaces/msg/Duration")


def package_texts(edition: str | None, msgs: str | None) -> dict[str, str]:
    """rosbags type name -> .msg text: the suite's edition, or the .msg and .srv files of a package folder."""
    if msgs is None:
        view = load_definitions().edition(edition or "seed")
        return {f"{PACKAGE}/msg/{m.name}": msg_text(m) for m in view.types.values() if m.definition.package == PACKAGE}
    return {f"{PACKAGE}/msg/{name}": text for name, text in read_package(Path(msgs)).items()}


class RosbagsAdapter:
    def __init__(self, edition: str | None = None, msgs: str | None = None):
        if edition is not None and msgs is not None:
            raise ValueError("give edition or msgs, not both")
        self.store = get_typestore(Stores.ROS1_NOETIC)
        types = {}
        for name, text in package_texts(edition, msgs).items():
            try:
                types.update(get_types_from_msg(text, name))
            except Exception as exc:  # rosbags' parser error, whatever its class
                raise ValueError(f"{name.replace('/msg/', '/')}: {exc}") from None
        self.store.register(types)
        self.source = f"{msgs} .msg files" if msgs else f"the suite's {edition or 'seed'} edition"
        self._builders: dict[str, tuple] = {}  # type -> (field names, [(name, convert in)], class)
        self._readers: dict[str, list] = {}  # type -> [(name, convert out)]

    def hello(self) -> dict:
        return {"implementation": f"rosbags {version('rosbags')} (typestore from {self.source})", "suites": [SUITE],
                "encodings": ["ros1"], "errata": "rosbags"}

    def _typename(self, full) -> str:
        package, _, name = str(full).partition("/")
        typename = f"{package}/msg/{name}"
        if typename not in self.store.types:
            raise Rejected(f"the typestore has no type {full!r}", rule="unknown-type")
        return typename

    # -------------------------------------------------------- encoding

    def encode(self, suite: str, message: dict, encoding: str) -> bytes:
        _check(suite, encoding)
        if not isinstance(message, dict):
            raise Rejected("a message must be an object", rule="value-type")
        typename = self._typename(message.get("type"))
        obj = self._build(typename, message.get("fields"))
        try:
            return bytes(self.store.serialize_ros1(obj, typename))
        except SerdeError as exc:
            raise Rejected(str(exc), rule="fixed-array-length" if "array length" in str(exc) else None) from exc
        except (struct.error, OverflowError) as exc:
            raise Rejected(str(exc), rule="value-type" if "not an integer" in str(exc) else "value-out-of-type") from exc

    def _build(self, typename: str, fields):
        if not isinstance(fields, dict):
            raise Rejected(f"{typename}: fields must be an object", rule="value-type")
        builder = self._builders.get(typename)
        if builder is None:
            defs = self.store.fielddefs[typename][1]
            builder = self._builders[typename] = ({name for name, _ in defs},
                                                  [(name, self._to(desc)) for name, desc in defs],
                                                  self.store.types[typename])
        names, converters, cls = builder
        if len(fields) != len(names) or not names.issuperset(fields):
            unknown = sorted(set(fields) - names)
            if unknown:
                raise Rejected(f"{typename} has no field {unknown[0]!r}", rule="unknown-field")
        values = {}
        for name, convert in converters:
            if name not in fields:
                raise Rejected(f"{typename}.{name} is missing", rule="missing-field")
            try:
                values[name] = convert(fields[name])
            except (ValueError, TypeError, KeyError) as exc:
                raise Rejected(f"{typename}.{name}: {exc}", rule="value-type") from exc
        return cls(**values)

    def _to(self, desc):
        """The function turning a decoded value of a field of ``desc`` into what rosbags takes."""
        kind, detail = desc
        if kind == Nodetype.BASE:
            base = detail[0]
            if base in FLOATS:  # a plain number goes as it is; strings (NaN by bits, infinities) are converted
                return lambda value: value if type(value) is float else _scalar(base, value)
            if base not in ("bool", "string"):
                return lambda value: value if type(value) is int else _scalar(base, value)
            return lambda value: _scalar(base, value)
        if kind == Nodetype.NAME:
            if detail in TIMES:
                cls = self.store.types[detail]
                return lambda value: cls(sec=value["secs"], nanosec=value["nsecs"])
            return lambda value: self._build(detail, value)
        element, _ = detail  # an ARRAY (fixed length) or SEQUENCE: rosbags wants numpy for primitives
        if element[0] == Nodetype.BASE and element[1][0] in DTYPES:
            base = element[1][0]
            return lambda value: _primitive_array(base, value)
        convert = self._to(element)

        def array(value):
            if not isinstance(value, list):
                raise Rejected("an array must be a list", rule="value-type")
            return [convert(v) for v in value]
        return array

    # -------------------------------------------------------- decoding

    def decode(self, suite: str, frame: bytes, type: str = "", encoding: str = "ros1") -> dict:
        _check(suite, encoding)
        typename = self._typename(type)
        try:
            obj = self.store.deserialize_ros1(frame, typename)
        except Exception as exc:  # SerdeError, and what a corrupt frame makes its readers raise
            raise Rejected(f"{exc.__class__.__name__}: {exc}") from exc
        return {"type": type, "fields": self._fields(typename, obj)}

    def _fields(self, typename: str, obj) -> dict:
        reader = self._readers.get(typename)
        if reader is None:
            reader = self._readers[typename] = [(name, self._from(desc)) for name, desc in self.store.fielddefs[typename][1]]
        return {name: convert(getattr(obj, name)) for name, convert in reader}

    def _from(self, desc):
        """The function turning a rosbags value of a field of ``desc`` into its decoded form."""
        kind, detail = desc
        if kind == Nodetype.BASE:
            base = detail[0]
            if base in FLOATS:  # finite values as they are (exact at the width); NaN and infinities by their bits
                width, pack = FLOATS[base], struct.Struct("<f" if base == "float32" else "<d").pack
                return lambda value: float(value) if isfinite(value) else float_from_bits(
                    int.from_bytes(pack(value), "little"), width)
            if base == "bool":
                return bool
            if base == "string":
                return lambda value: value
            return lambda value: int_form(int(value))
        if kind == Nodetype.NAME:
            if detail in TIMES:
                return lambda value: {"secs": int(value.sec), "nsecs": int(value.nanosec)}
            return lambda value: self._fields(detail, value)
        element, _ = detail
        if element[0] == Nodetype.BASE and element[1][0] in DTYPES:
            base = element[1][0]
            return lambda value: _from_primitive_array(base, value)
        convert = self._from(element)
        return lambda value: [convert(v) for v in value]

    # -------------------------------------------------------- definitions

    def describe(self, suite: str, type: str = "") -> dict:
        _check(suite, "ros1")
        text, md5 = self.store.generate_msgdef(self._typename(type), ros_version=1)
        return {"md5": md5, "definition": text}


def _check(suite: str, encoding: str) -> None:
    if suite != SUITE:
        raise Unsupported(f"suite {suite!r}")
    if encoding != "ros1":
        raise Unsupported(f"encoding {encoding!r}")


def _scalar(base: str, value):
    if base == "bool":
        if not isinstance(value, bool):
            raise Rejected(f"{value!r} is not a boolean", rule="value-type")
        return value
    if base in FLOATS:
        width = FLOATS[base]
        return struct.unpack("<" + ("f" if width == 4 else "d"), float_to_bits(value, width).to_bytes(width, "little"))[0]
    if base == "string":
        if not isinstance(value, str):
            raise Rejected("rosbags strings are text: this one is not UTF-8", rule="value-type")
        return value
    number = int_value(value)
    if number is None:
        raise Rejected(f"{value!r} is not an integer", rule="value-type")
    return number


def _primitive_array(base: str, value) -> np.ndarray:
    if base == "uint8":
        return np.frombuffer(bytes.fromhex(value), dtype=np.uint8).copy()
    if not isinstance(value, list):
        raise Rejected("an array must be a list", rule="value-type")
    if base in FLOATS:  # by bits, so that NaN payloads survive
        width = FLOATS[base]
        raw = b"".join(float_to_bits(v, width).to_bytes(width, "little") for v in value)
        return np.frombuffer(raw, dtype=DTYPES[base]).copy()
    items = [_scalar(base, v) for v in value]
    try:
        return np.array(items, dtype=DTYPES[base])
    except OverflowError as exc:
        raise Rejected(str(exc), rule="value-out-of-type") from exc


def _from_primitive_array(base: str, value) -> object:
    if base == "uint8":
        return bytes(value).hex()
    if base in FLOATS:
        width = FLOATS[base]
        raw = np.asarray(value, dtype=DTYPES[base]).tobytes()
        return [float_from_bits(int.from_bytes(raw[i:i + width], "little"), width) for i in range(0, len(raw), width)]
    if base == "bool":
        return [bool(v) for v in value]
    return [int_form(int(v)) for v in value]
