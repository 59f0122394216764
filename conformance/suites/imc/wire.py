"""IMC frames for the scenario engine: composing what a step sends (header addressed from the run), parsing
what a node sends (with the byte-level rules of the reference codec), and enumeration names both ways."""

from __future__ import annotations

import struct

from ...kinds.scenario import Addressing, Composed, Parsed
from ...kinds.vector.errors import FrameError, NotJudged
from . import codec
from .crc16 import crc16
from .definitions import Definitions, MessageDef
from .elsewhere import defined_elsewhere

UNKNOWN_SYSTEM, UNKNOWN_ENTITY = 0xFFFF, 0xFF
DATAGRAM_LIMIT = 65507  # bytes an IPv4 UDP datagram carries
NOT_JUDGED_CLAUSE = "imc-wire#field-types"  # what a frame the reference codec does not judge is about (inline messages)


def outside(defs: Definitions, mgid: int) -> tuple[str, bool]:
    """(its name in reports, whether no definition names it) for a sound frame whose message id the definitions
    lack: a vehicle's other traffic (an id IMC.xml defines: ``ids_elsewhere``, named as the whole IMC.xml in the
    cache names it, else by its id), or an id no IMC.xml the suite has defines (a newer protocol, a private message).
    Both are judged no further than their framing."""
    mdef = defs.by_id.get(mgid)
    if mdef is not None:
        return mdef.abbrev, False
    if mgid not in defs.ids_elsewhere:
        return f"id {mgid}", True
    whole = defined_elsewhere(mgid)
    return (whole.abbrev if isinstance(whole, MessageDef) else f"id {mgid}"), False


class ImcWire:
    transport = "datagram"
    anyone = UNKNOWN_SYSTEM  # 0xFFFF: unknown, or anyone (imc-wire.md, defaults)
    outside_judged = "framing checked only"  # what is judged of a frame of a message outside the suite

    def __init__(self, defs: Definitions, rule_clauses: dict[str, str]):
        self.defs, self.rule_clauses = defs, rule_clauses

    def compose(self, message: dict, encoding: str | None, addressing: Addressing, epoch: float,
                step: str = "", edition: str | None = None) -> Composed:
        header = {"timestamp": float(epoch), "src": UNKNOWN_SYSTEM if addressing.system is None else addressing.system,
                  "src_ent": UNKNOWN_ENTITY if addressing.entity is None else addressing.entity,
                  "dst": UNKNOWN_SYSTEM if addressing.node is None else addressing.node, "dst_ent": UNKNOWN_ENTITY}
        header.update(message.get("header", {}))
        order, damaged = _encoding(encoding)
        frame = codec.encode(self.defs, {"abbrev": message["abbrev"], "header": header, "fields": message["fields"]}, order)
        if len(frame) > DATAGRAM_LIMIT:
            raise ValueError(f"the {message['abbrev']} frame is {len(frame)} bytes: one UDP datagram carries {DATAGRAM_LIMIT}")
        decoded = codec.decode(self.defs, frame)  # what the frame says: a damaged CRC changes no field
        if damaged:
            frame = frame[:-2] + bytes(b ^ 0xFF for b in frame[-2:])
        return Composed(frame, decoded, message["abbrev"], encoding or "le",
                        {"step": step, **({"damaged": "crc"} if damaged else {})})

    def parse(self, data: bytes) -> Parsed:
        try:
            decoded = codec.decode(self.defs, data, elsewhere=defined_elsewhere)
        except FrameError as exc:
            mgid = self.id_in_header(data) if exc.rule == "unknown-id" else None
            if mgid is not None and mgid != self.defs.null_id:  # sound (decode checks the CRC first), not ours
                name, undefined = outside(self.defs, mgid)
                return Parsed(data, None, encoding=codec.byte_order_of(data), outside=name, undefined=undefined)
            return Parsed(data, self.named_in_header(data), None, f"{exc.rule} at byte {exc.offset}: {exc.detail}",
                          self.rule_clauses.get(exc.rule), codec.byte_order_of(data),
                          addressed=self.addressed_in_header(data))
        except NotJudged as exc:
            return Parsed(data, self.named_in_header(data), None, f"{exc.reason} at byte {exc.offset}: {exc.detail}",
                          NOT_JUDGED_CLAUSE, codec.byte_order_of(data), undecided=True)
        return Parsed(data, decoded["abbrev"], decoded, encoding=codec.byte_order_of(data))

    def knows(self, message: str) -> bool:
        return message in self.defs.by_abbrev

    def fields_of(self, message: str) -> list[str]:
        return [f.abbrev for f in self.defs[message].fields]

    def example(self, message: str, edition: str) -> dict:
        defaults = {"plaintext": "", "rawdata": "", "message": None, "message-list": []}
        return {f.abbrev: 0.0 if f.is_float else defaults.get(f.type, 0) for f in self.defs[message].fields}

    def setup(self, service: str, state: dict, step: str):
        raise ValueError("an IMC node over UDP has no handler to set up")

    def reply(self, composed, answer):
        raise ValueError("an IMC node answers over the link, not through calls")

    def readdress(self, data: bytes, encoding: str, src: tuple[int, int], dst: int) -> bytes:
        """A corpus frame as if the session sent it to the node: header src/src_ent and dst rewritten (in the
        frame's byte order ``encoding``) and its CRC recomputed with the case's defect kept (a frame whose CRC
        was wrong by some bits stays wrong by the same bits). Frames too short for a header are unchanged."""
        if len(data) < codec.HEADER_SIZE:
            return data
        e = codec.ORDERS[encoding]
        out = bytearray(data)
        (size,) = struct.unpack_from(e + "H", data, 4)
        end = codec.HEADER_SIZE + size if codec.HEADER_SIZE + size + 2 <= len(data) else len(data) - 2
        delta = None
        if end >= codec.HEADER_SIZE:
            (stored,) = struct.unpack_from(e + "H", data, end)
            delta = stored ^ crc16(data[:end])
        struct.pack_into(e + "HBH", out, 14, src[0], src[1], dst)
        if delta is not None:
            struct.pack_into(e + "H", out, end, crc16(out[:end]) ^ delta)
        return bytes(out)

    def garbage(self, rng, count: int, src: tuple[int, int], dst: int) -> list[bytes]:
        """``count`` datagrams a receiver must drop, from the generator ``rng``: random bytes; the sync word in
        either byte order followed by random bytes; and frames from ``src`` to ``dst`` with a sound header and
        CRC around a random payload of a real or unknown message id, which reach the payload decoder (kept only
        if the reference codec refuses them, so none is a valid request)."""
        ids = sorted(self.defs.by_id)
        out = []
        while len(out) < count:
            kind = len(out) % 3
            if kind == 0:
                out.append(rng.randbytes(rng.randrange(1, 600)))
                continue
            order = rng.choice(("<", ">"))
            if kind == 1:
                out.append(struct.pack(order + "H", self.defs.sync) + rng.randbytes(rng.randrange(0, 300)))
                continue
            mgid = rng.choice(ids) if rng.random() < 0.8 else rng.randrange(0, 0x10000)
            payload = rng.randbytes(rng.randrange(0, 200))
            body = struct.pack(order + "HHHdHBHB", self.defs.sync, mgid, len(payload), 0.0, src[0], src[1], dst,
                               0xFF) + payload
            frame = body + struct.pack(order + "H", crc16(body))
            try:
                codec.decode(self.defs, frame)
            except FrameError:
                out.append(frame)
        return out

    def id_in_header(self, data: bytes) -> int | None:
        """The message id a frame's header holds, if it can be read (in the byte order its sync names)."""
        order = codec.byte_order_of(data)
        if order is None or len(data) < 4:
            return None
        return struct.unpack_from(codec.ORDERS[order] + "H", data, 2)[0]

    def named_in_header(self, data: bytes) -> str | None:
        """The message a frame's header names, if it can be read (even when the frame is malformed)."""
        mgid = self.id_in_header(data)
        if mgid is None:
            return None
        mdef = self.defs.by_id.get(mgid)
        return mdef.abbrev if mdef is not None and not mdef.auxiliary else None

    def addressed_in_header(self, data: bytes) -> tuple | None:
        """(dst, dst_ent) a frame's header names, if it holds a whole header (even when the frame is malformed)."""
        order = codec.byte_order_of(data)
        if order is None or len(data) < codec.HEADER_SIZE:
            return None
        return struct.unpack_from(codec.ORDERS[order] + "HB", data, 17)

    def resolve(self, message: str, path: str, value, edition: str):
        field = self.defs[message].field(path)
        if not isinstance(value, str) or not field.enum_values or field.type in ("plaintext", "rawdata"):
            return value
        for v in field.enum_values:
            if v.abbrev == value and v.in_edition(edition):
                return v.value
        raise KeyError(f"{value} is not a value of {message}.{path} in {edition}")

    def size_of(self, message: str, path: str, value) -> int:
        mdef = self.defs[message]
        return len(codec.encode_field(self.defs, mdef, mdef.field(path), value, "<"))

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


def _encoding(encoding: str | None) -> tuple[str, bool]:
    """A send step's encoding: the byte order (le, be) and whether the frame's CRC is to be damaged (le-bad-crc,
    be-bad-crc: every bit of the stored CRC flipped, so the frame is invalid by that one rule)."""
    order, _, damage = (encoding or "le").partition("-")
    if order not in codec.ORDERS or damage not in ("", "bad-crc"):
        raise ValueError(f"unknown encoding {encoding!r}: le, be, le-bad-crc or be-bad-crc")
    return order, bool(damage)
