"""ros_acomms_msgs definitions, loaded from the language-neutral data under ``vectors/ros_acomms``.

A type is a message, or one half (request, response) of a service; ``RosDefinitions.edition(name)`` is
the set of types as one edition has them (fields and types that exist only in some editions filtered),
which the codec, the text and MD5 functions and the corpus generator work on.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass
from functools import cache, cached_property
from pathlib import Path

from .paths import ros_data

# ROS 1 primitive -> (struct code, size); string, time and duration have their own encodings.
PRIMITIVES = {
    "bool": ("?", 1), "int8": ("b", 1), "uint8": ("B", 1), "int16": ("h", 2), "uint16": ("H", 2),
    "int32": ("i", 4), "uint32": ("I", 4), "int64": ("q", 8), "uint64": ("Q", 8), "float32": ("f", 4),
    "float64": ("d", 8),
}
BUILTINS = (*PRIMITIVES, "string", "time", "duration")
TYPE_SYNTAX = re.compile(r"^([A-Za-z][A-Za-z0-9_]*(?:/[A-Za-z][A-Za-z0-9_]*)?)(?:\[(\d*)\])?$")


class DefinitionError(ValueError):
    """A definition that cannot be used (an unknown type, a bad type reference)."""


@dataclass(frozen=True)
class FieldType:
    """``base``: a builtin or a message type's full name (``pkg/Name``); ``array``: None (scalar), -1
    (variable length) or the fixed length."""

    base: str
    array: int | None = None

    @property
    def is_builtin(self) -> bool:
        return self.base in BUILTINS

    @property
    def element(self) -> FieldType:
        return FieldType(self.base)

    def text(self, package: str) -> str:
        """As a .msg file writes it: a message type of ``package`` unqualified."""
        base = self.base.split("/", 1)[1] if self.base.startswith(package + "/") else self.base
        return base + ("" if self.array is None else "[]" if self.array < 0 else f"[{self.array}]")


def parse_type(text: str, package: str) -> FieldType:
    """A type reference as .msg files write it (``int16``, ``CST[]``, ``bool[4]``, ``std_msgs/Header``)."""
    match = TYPE_SYNTAX.match(text.strip())
    if not match:
        raise DefinitionError(f"{text!r} is not a type")
    base, size = match[1], match[2]
    if base not in BUILTINS:
        base = "std_msgs/Header" if base == "Header" else base if "/" in base else f"{package}/{base}"
    return FieldType(base, None if size is None else -1 if size == "" else int(size))


@dataclass(frozen=True)
class Field:
    name: str
    type: FieldType
    editions: tuple[str, ...] | None = None  # None: every edition
    source: str | None = None  # where a fact the seed does not show comes from


@dataclass(frozen=True)
class Constant:
    type: str
    name: str
    value: str
    source: str | None = None


@dataclass(frozen=True)
class TypeDef:
    """A message type, or a service's request or response, with the fields of every edition."""

    name: str
    package: str
    kind: str  # "msg" | "request" | "response"
    clause: str
    constants: tuple[Constant, ...]
    fields: tuple[Field, ...]
    service: str | None = None
    editions: tuple[str, ...] | None = None  # None: every edition
    auxiliary: bool = False  # nested by the suite's types but not one of them (std_msgs/Header)
    comment: str = ""

    @property
    def full(self) -> str:
        return f"{self.package}/{self.name}"

    def in_edition(self, edition: str) -> bool:
        return self.editions is None or edition in self.editions


@dataclass(frozen=True)
class Message:
    """A type as one edition has it."""

    definition: TypeDef
    fields: tuple[Field, ...]

    @property
    def full(self) -> str:
        return self.definition.full

    @property
    def name(self) -> str:
        return self.definition.name


class Edition:
    """The types of one edition, by full name."""

    def __init__(self, name: str, types: dict[str, Message]):
        self.name, self.types = name, types

    def __getitem__(self, full: str) -> Message:
        return self.types[full]

    def __contains__(self, full) -> bool:
        return full in self.types

    def dependencies(self, message: Message) -> list[Message]:
        """The message types ``message`` nests, depth first, each once (genmsg's order)."""
        out: list[Message] = []

        def visit(m: Message) -> None:
            for f in m.fields:
                if not f.type.is_builtin and all(d.full != f.type.base for d in out):
                    inner = self.types[f.type.base]
                    out.append(inner)
                    visit(inner)
        visit(message)
        return out


@dataclass(frozen=True)
class RosDefinitions:
    package: str
    editions: tuple[str, ...]
    types: tuple[TypeDef, ...]

    @cached_property
    def by_full(self) -> dict[str, TypeDef]:
        return {t.full: t for t in self.types}

    @property
    def suite_types(self) -> tuple[TypeDef, ...]:
        """The types the suite covers (auxiliary ones excluded)."""
        return tuple(t for t in self.types if not t.auxiliary)

    @cached_property
    def _views(self) -> dict[str, Edition]:
        return {}

    def edition(self, name: str) -> Edition:
        """The types as edition ``name`` has them (built once per definitions object)."""
        view = self._views.get(name)
        if view is None:
            if name not in self.editions:
                raise DefinitionError(f"unknown edition {name!r}")
            types = {t.full: Message(t, tuple(f for f in t.fields if f.editions is None or name in f.editions))
                     for t in self.types if t.in_edition(name)}
            for m in types.values():
                for f in m.fields:
                    if not f.type.is_builtin and f.type.base not in types:
                        raise DefinitionError(f"{m.full}.{f.name}: type {f.type.base} is not defined in edition {name}")
            view = self._views[name] = Edition(name, types)
        return view


def parse_definitions(raw: dict) -> RosDefinitions:
    package = raw["package"]
    types = tuple(
        TypeDef(name=t["name"], package=t["package"], kind=t["kind"], clause=t["clause"],
                constants=tuple(Constant(c["type"], c["name"], c["value"], c.get("source")) for c in t["constants"]),
                fields=tuple(Field(f["name"], parse_type(f["type"], t["package"]),
                                   tuple(f["editions"]) if "editions" in f else None, f.get("source"))
                             for f in t["fields"]),
                service=t.get("service"), editions=tuple(t["editions"]) if "editions" in t else None,
                auxiliary=t.get("auxiliary", False), comment=t.get("comment", ""))
        for t in raw["types"])
    return RosDefinitions(package, tuple(e["name"] for e in raw["editions"]), types)


@cache
def load_definitions(path: Path | None = None) -> RosDefinitions:
    path = path or ros_data("definitions.json")
    return parse_definitions(json.loads(Path(path).read_text(encoding="utf-8")))
