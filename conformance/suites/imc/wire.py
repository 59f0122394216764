"""IMC frames for the scenario engine: composing what a step sends (header addressed from the run), parsing
what a node sends (with the byte-level rules of the reference codec), and enumeration names both ways."""

from __future__ import annotations

import struct

from ...kinds.scenario import Addressing, Composed, Parsed
from ...kinds.vector.errors import FrameError
from . import codec
from .definitions import Definitions, MessageDef

UNKNOWN_SYSTEM, UNKNOWN_ENTITY = 0xFFFF, 0xFF


class ImcWire:
    def __init__(self, defs: Definitions, rule_clauses: dict[str, str]):
        self.defs, self.rule_clauses = defs, rule_clauses

    def compose(self, message: dict, encoding: str | None, addressing: Addressing, epoch: float) -> Composed:
        header = {"timestamp": float(epoch), "src": addressing.system, "src_ent": addressing.entity,
                  "dst": UNKNOWN_SYSTEM if addressing.node is None else addressing.node, "dst_ent": UNKNOWN_ENTITY}
        header.update(message.get("header", {}))
        frame = codec.encode(self.defs, {"abbrev": message["abbrev"], "header": header, "fields": message["fields"]},
                             encoding or "le")
        return Composed(frame, codec.decode(self.defs, frame), message["abbrev"], encoding or "le")

    def parse(self, data: bytes) -> Parsed:
        try:
            decoded = codec.decode(self.defs, data)
        except FrameError as exc:
            return Parsed(data, self.named_in_header(data), None, f"{exc.rule} at byte {exc.offset}: {exc.detail}",
                          self.rule_clauses.get(exc.rule), codec.byte_order_of(data))
        return Parsed(data, decoded["abbrev"], decoded, encoding=codec.byte_order_of(data))

    def named_in_header(self, data: bytes) -> str | None:
        """The message a frame's header names, if it can be read (even when the frame is malformed)."""
        order = codec.byte_order_of(data)
        if order is None or len(data) < 4:
            return None
        (mgid,) = struct.unpack_from(codec.ORDERS[order] + "H", data, 2)
        mdef = self.defs.by_id.get(mgid)
        return mdef.abbrev if mdef is not None and not mdef.auxiliary else None

    def resolve(self, message: str, path: str, value, edition: str):
        field = self.defs[message].field(path)
        if not isinstance(value, str) or not field.enum_values or field.type in ("plaintext", "rawdata"):
            return value
        for v in field.enum_values:
            if v.abbrev == value and v.in_edition(edition):
                return v.value
        raise KeyError(f"{value} is not a value of {message}.{path} in {edition}")

    def origin(self, parsed: Parsed) -> tuple | None:
        header = parsed.decoded["header"]
        return header["src"], header["src_ent"]

    def destination(self, parsed: Parsed) -> tuple | None:
        header = parsed.decoded["header"]
        return header["dst"], header["dst_ent"]

    def present(self, item) -> dict:
        out = {"message": item.message} if item.message else {}
        if item.decoded is not None:
            if "header" in item.decoded:
                out["header"] = item.decoded["header"]
            mdef = self.defs.by_abbrev.get(item.message)
            fields = item.decoded.get("fields", {})
            out["fields"] = self.named(mdef, fields) if mdef else fields
        if isinstance(item.data, (bytes, bytearray)):
            out["bytes"] = bytes(item.data).hex()
        return out

    def named(self, mdef: MessageDef, fields: dict) -> dict:
        """Fields with enumeration values by name (``NAME`` or the number when it has none)."""
        out = {}
        for key, value in fields.items():
            try:
                f = mdef.field(key)
            except KeyError:
                out[key] = value
                continue
            if f.enum_kind == "enum" and isinstance(value, int):
                names = [v.abbrev for v in f.enum_values if v.value == value]
                out[key] = names[0] if names else value
            elif isinstance(value, dict) and value.get("abbrev") in self.defs.by_abbrev:
                out[key] = {"abbrev": value["abbrev"], "fields": self.named(self.defs[value["abbrev"]], value["fields"])}
            elif isinstance(value, list):
                out[key] = [{"abbrev": v["abbrev"], "fields": self.named(self.defs[v["abbrev"]], v["fields"])}
                            if isinstance(v, dict) and v.get("abbrev") in self.defs.by_abbrev else v for v in value]
            else:
                out[key] = value
        return out
