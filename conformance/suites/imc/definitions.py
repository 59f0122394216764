"""IMC message definitions, loaded from the language-neutral data under ``vectors/imc``."""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass, field
from functools import cache, cached_property
from pathlib import Path

from .paths import imc_data

SCALAR_FORMATS = {
    "int8_t": "b", "uint8_t": "B", "int16_t": "h", "uint16_t": "H",
    "int32_t": "i", "uint32_t": "I", "int64_t": "q", "fp32_t": "f", "fp64_t": "d",
}


@dataclass(frozen=True)
class EnumValue:
    value: int
    abbrev: str
    name: str | None  # absent where the source gives only the abbreviation
    editions: tuple[str, ...] | None  # None: every edition
    source: str

    def in_edition(self, edition: str) -> bool:
        return self.editions is None or edition in self.editions


@dataclass(frozen=True)
class FieldDef:
    abbrev: str
    name: str
    type: str
    clause: str
    unit: str | None = None
    minimum: float | None = None
    maximum: float | None = None
    enum_kind: str | None = None  # "enum" | "bitfield"
    enum_values: tuple[EnumValue, ...] = ()
    message_types: tuple[str, ...] = ()
    range_source: str | None = None  # clause of min/max when it differs from the field's

    @cached_property
    def is_scalar(self) -> bool:
        return self.type in SCALAR_FORMATS

    @cached_property
    def is_float(self) -> bool:
        return self.type in ("fp32_t", "fp64_t")

    @cached_property
    def is_int(self) -> bool:
        return self.is_scalar and not self.is_float

    @cached_property
    def size(self) -> int:
        """Bytes of a scalar field."""
        return {"b": 1, "B": 1, "h": 2, "H": 2, "i": 4, "I": 4, "q": 8, "f": 4, "d": 8}[SCALAR_FORMATS[self.type]]

    @cached_property
    def int_bounds(self) -> tuple[int, int]:
        bits = 8 * self.size
        if self.type.startswith("u"):
            return 0, (1 << bits) - 1
        return -(1 << (bits - 1)), (1 << (bits - 1)) - 1

    @cached_property
    def int_range(self) -> tuple[int, int]:
        """The integers an integer field may hold: its type's, narrowed by its min and max."""
        lo, hi = self.int_bounds
        if self.minimum is not None:
            lo = max(lo, math.ceil(self.minimum))
        if self.maximum is not None:
            hi = min(hi, math.floor(self.maximum))
        return lo, hi


@dataclass(frozen=True)
class MessageDef:
    id: int
    abbrev: str
    name: str
    clause: str
    fields: tuple[FieldDef, ...]
    min_payload: int
    flags: tuple[str, ...] = ()
    auxiliary: bool = False  # named by the seeds' messages but not one of them (DevDataBinary)

    @cached_property
    def hash(self) -> str:
        """Hash of the wire-relevant definition: id, abbrev, and each field's abbrev and type in order."""
        canon = {"id": self.id, "abbrev": self.abbrev, "fields": [[f.abbrev, f.type] for f in self.fields]}
        text = json.dumps(canon, sort_keys=True, separators=(",", ":"))
        return "sha256:" + hashlib.sha256(text.encode()).hexdigest()[:16]

    def field(self, abbrev: str) -> FieldDef:
        for f in self.fields:
            if f.abbrev == abbrev:
                return f
        raise KeyError(f"{self.abbrev} has no field {abbrev!r}")


@dataclass(frozen=True)
class Definitions:
    """All messages of one protocol description, indexed by id and abbreviation."""

    messages: tuple[MessageDef, ...]
    editions: tuple[str, ...]
    sync: int
    max_payload: int
    null_id: int
    header_defaults: dict
    raw: dict = field(repr=False, compare=False)
    ids_elsewhere: frozenset[int] = frozenset()  # ids IMC.xml defines and these definitions do not

    @cached_property
    def by_id(self) -> dict[int, MessageDef]:
        return {m.id: m for m in self.messages}

    @cached_property
    def by_abbrev(self) -> dict[str, MessageDef]:
        return {m.abbrev: m for m in self.messages}

    def __getitem__(self, key: int | str) -> MessageDef:
        return self.by_id[key] if isinstance(key, int) else self.by_abbrev[key]

    @property
    def suite_messages(self) -> tuple[MessageDef, ...]:
        """The messages the suite covers (auxiliary definitions excluded)."""
        return tuple(m for m in self.messages if not m.auxiliary)


def _field(raw: dict) -> FieldDef:
    enum = raw.get("enum") or {}
    values = tuple(
        EnumValue(v["value"], v["abbrev"], v.get("name"), tuple(v["editions"]) if "editions" in v else None,
                  v.get("source", enum.get("source", raw["clause"])))
        for v in enum.get("values", ())
    )
    return FieldDef(
        abbrev=raw["abbrev"], name=raw["name"], type=raw["type"], clause=raw["clause"], unit=raw.get("unit"),
        minimum=raw.get("min"), maximum=raw.get("max"), enum_kind=enum.get("kind"), enum_values=values,
        message_types=tuple((raw.get("message_type") or {}).get("values", ())),
        range_source=raw.get("range_source", raw["clause"]),
    )


def parse_definitions(raw: dict) -> Definitions:
    frame = raw["frame"]
    messages = tuple(
        MessageDef(
            id=m["id"], abbrev=m["abbrev"], name=m["name"], clause=m["clause"],
            fields=tuple(_field(f) for f in m["fields"]), min_payload=m["min_payload"]["value"],
            flags=tuple((m.get("flags") or {}).get("values", ())), auxiliary=m.get("auxiliary", False),
        )
        for m in raw["messages"]
    )
    return Definitions(
        messages=messages, editions=tuple(raw["editions"]), sync=frame["sync"]["value"],
        max_payload=frame["max_payload"]["value"], null_id=frame["null_message_id"]["value"],
        header_defaults={k: v for k, v in frame["header_defaults"].items() if k != "source"}, raw=raw,
        ids_elsewhere=frozenset((frame.get("ids_elsewhere") or {}).get("values", ())),
    )


@cache
def load_definitions(path: Path | None = None) -> Definitions:
    path = path or imc_data("definitions.json")
    return parse_definitions(json.loads(Path(path).read_text(encoding="utf-8")))


def lint_definitions(defs: Definitions) -> list[str]:
    """Problems in the definitions themselves, such as an enum value that cannot fit its field's type."""
    problems = []
    for m in defs.messages:
        for f in m.fields:
            for v in f.enum_values:
                lo, hi = f.int_bounds if f.is_int else (None, None)
                if lo is not None and not lo <= v.value <= hi:
                    editions = ", ".join(v.editions or defs.editions)
                    problems.append(
                        f"{m.abbrev}.{f.abbrev}: {v.abbrev} = {v.value} does not fit {f.type} "
                        f"[{lo}, {hi}] (editions: {editions})"
                    )
                elif not f.int_range[0] <= v.value <= f.int_range[1]:
                    problems.append(f"{m.abbrev}.{f.abbrev}: {v.abbrev} = {v.value} is outside the field's min/max "
                                    f"[{f.minimum}, {f.maximum}]: its cases are acceptable")
            for t in f.message_types:
                if t not in defs.by_abbrev:
                    problems.append(f"{m.abbrev}.{f.abbrev}: message type {t} is not defined")
    return problems
