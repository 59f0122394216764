"""The IMC fuzz source: hypothesis strategies of every message from the definitions, and frame mutations that each
aim at one framing rule. No per-message code: every strategy follows a field's type, enumeration, bitfield, range
and inline types.

Generated messages stay valid under the edition (enumerations from its table, bitfields of defined bits, floats
within a declared range, ASCII plaintext, inline messages of the declared types), so that each is a ``valid`` case
in both byte orders. A mutated frame is judged by the reference: refused (``invalid``, with its rule), or decoded
to a message that is ``valid`` or, when it holds what the corpus files as implementation-defined (an enumeration
value out of the table, an undefined bit, a float out of range, non-ASCII text, an inline message of another type,
a null list element, bytes after the fields or the footer; and, for a message to encode, a zero timestamp),
``acceptable``, with the outcomes its classes of rules.json permit.
"""

from __future__ import annotations

import struct
from functools import cached_property

from hypothesis import strategies as st

from ...fuzz.source import filed, pins_nan, sized_lists
from ...kinds.vector.errors import EncodeError, FrameError, NotJudged
from ...kinds.vector.floats import FLOAT_CLASSES
from . import codec
from .codec import FOOTER_SIZE, HEADER_SIZE, ORDERS
from .corpus.acceptable import classes, outcomes
from .corpus.samples import ORDINARY_HEADER
from .corpus.records import ALL_CHECKS
from .crc16 import crc16
from .decoded_form import used_abbrevs
from .definitions import Definitions, FieldDef, MessageDef

MAX_DEPTH = 2  # inline messages nest at most this deep in generated messages
MAX_TEXT = 300  # bytes of a generated plaintext or rawdata
MAX_LIST = 6  # elements of a generated message-list at the top level (fewer deeper)
# The class of rules.json each acceptable reason (a tag errata are filed by) belongs to.
CLASSES = {"out-of-table": "enum-out-of-table", "undefined-bit": "bitfield-undefined", "out-of-range": "out-of-range",
           "non-ascii": "non-ascii-text", "null-element": "null-list-element", "wrong-type": "wrong-inline-type",
           "trailing-bytes": "trailing-bytes", "unused-payload": "unused-payload", "zero-timestamp": "zero-timestamp"}
MUTATIONS = ("bit-flip", "truncate", "extend", "size-past-data", "prefix-past-data", "sync", "crc", "id-neighbour",
             "inline-id-neighbour", "payload-byte")


def fp32(x: float) -> float:
    return struct.unpack("<f", struct.pack("<f", x))[0]


def float_strategy(f: FieldDef):
    width = 32 if f.size == 4 else 64
    if f.minimum is not None or f.maximum is not None:  # ranged: finite values within it (outside is acceptable)
        lo, hi = f.minimum, f.maximum
        if width == 32:  # the representable bounds inside the range
            lo = None if lo is None else next(v for v in (fp32(lo), _toward(fp32(lo), +1)) if v >= lo)
            hi = None if hi is None else next(v for v in (fp32(hi), _toward(fp32(hi), -1)) if v <= hi)
        return st.floats(lo, hi, width=width, allow_nan=False, allow_infinity=False)
    specials = [v[0 if width == 32 else 1] for v in FLOAT_CLASSES.values()]
    nan_bits = (st.integers(1, (1 << 23) - 1).map(lambda m: f"nan:{0x7F800000 | m:08x}") if width == 32 else
                st.integers(1, (1 << 52) - 1).map(lambda m: f"nan:{0x7FF0000000000000 | m:016x}"))
    everyday = st.floats(-1e6, 1e6, width=width)  # the magnitudes real fields carry, densely
    return st.one_of(st.floats(width=width, allow_nan=False), everyday, st.sampled_from(specials), nan_bits)


def ascii_text(data: bytes) -> str:
    return data.translate(TO_ASCII).decode("ascii")


TO_ASCII = bytes(b & 0x7F for b in range(256))


def _toward(x: float, direction: int) -> float:
    bits = struct.unpack("<i", struct.pack("<f", x))[0]
    bits += direction if x >= 0 else -direction
    return struct.unpack("<f", struct.pack("<i", bits))[0]


class ImcFuzzSource:
    """Strategies and mutations for every message of one edition of the IMC definitions."""

    suite = "imc"
    mutations = MUTATIONS

    def __init__(self, defs: Definitions, edition: str, clauses: dict[str, str],
                 corpus_frames: dict[str, list[tuple[str, bytes]]] | None = None):
        self.defs, self.edition, self.clauses = defs, edition, clauses
        self.groups = tuple(m.abbrev for m in defs.suite_messages)
        self._strategies: dict[tuple[str, int], object] = {}
        self._seed_frames = corpus_frames or {}

    # ------------------------------------------------------------ strategies

    @cached_property
    def header(self):
        return st.fixed_dictionaries({
            "timestamp": st.one_of(st.floats(allow_nan=False, allow_infinity=False), st.just(-0.0)),
            "src": st.integers(0, 0xFFFF), "src_ent": st.integers(0, 0xFF),
            "dst": st.integers(0, 0xFFFF), "dst_ent": st.integers(0, 0xFF)})

    def fields(self, mdef: MessageDef, depth: int):
        key = (mdef.abbrev, depth)
        if key not in self._strategies:
            self._strategies[key] = st.fixed_dictionaries({f.abbrev: self.value(f, depth) for f in mdef.fields})
        return self._strategies[key]

    def value(self, f: FieldDef, depth: int):
        if f.enum_kind == "enum":
            lo, hi = f.int_bounds
            values = [v.value for v in f.enum_values if v.in_edition(self.edition) and lo <= v.value <= hi]
            return st.sampled_from(values)
        if f.enum_kind == "bitfield":
            bits = [v.value for v in f.enum_values]
            return st.lists(st.sampled_from(bits), unique=True).map(_or)
        if f.is_int:  # hypothesis's integers already favour the bounds, zero and small values
            lo, hi = f.int_bounds
            return st.integers(lo, hi)
        if f.is_float:
            return float_strategy(f)
        if f.type == "plaintext":  # drawn as bytes (one choice, not one per character), folded into ASCII
            return st.binary(max_size=MAX_TEXT).map(ascii_text)
        if f.type == "rawdata":
            return st.binary(max_size=MAX_TEXT).map(bytes.hex)
        inner = self.inner_types(f)
        if f.type == "message":
            if depth >= MAX_DEPTH:
                return st.none()
            return st.one_of(st.none(), *(self.inline(m, depth + 1) for m in inner))
        if depth >= MAX_DEPTH:
            return st.just([])
        element = st.one_of(*(self.inline(m, depth + 1) for m in inner))
        return sized_lists(element, MAX_LIST if depth == 0 else 2)

    def inline(self, mdef: MessageDef, depth: int):
        return st.deferred(lambda: self.fields(mdef, depth)).map(lambda fields, a=mdef.abbrev: {"abbrev": a, "fields": fields})

    def inner_types(self, f: FieldDef) -> list[MessageDef]:
        """The types an inline field or list may hold: its declared ones, else every message of the suite."""
        return [self.defs[t] for t in f.message_types] if f.message_types else list(self.defs.suite_messages)

    def message(self, group: str):
        mdef = self.defs[group]
        return st.fixed_dictionaries({"abbrev": st.just(group), "header": self.header, "fields": self.fields(mdef, 0)})

    def inputs(self, group: str, prop: str):
        if prop == "message":
            return self.message(group)
        return st.fixed_dictionaries({
            "message": self.message(group), "encoding": st.sampled_from(("le", "be")),
            "mutation": st.sampled_from(MUTATIONS), "a": st.integers(0, 1 << 16), "b": st.integers(0, 1 << 16)})

    # ------------------------------------------------------------ cases

    def case(self, group: str, prop: str, drawn) -> dict | None:
        if prop == "message":
            try:
                frames = {o: codec.encode(self.defs, drawn, o) for o in ("le", "be")}
            except EncodeError:  # e.g. a payload over the size limit: not a valid message
                return None
            canonical = codec.decode(self.defs, frames["le"])
            reasons = self.acceptable_reasons(canonical) + (  # a promoted message rebuilt in another edition
                ["zero-timestamp"] if canonical["header"]["timestamp"] == 0 else [])
            if reasons:
                return self.record(group, "acceptable", self.defs[group].clause, ALL_CHECKS,
                                   ["acceptable", "fuzz", *reasons, *self.tags(canonical)], frames=frames,
                                   message=canonical, compare=pins_nan(canonical), **acceptable_fields(reasons))
            return self.record(group, "valid", self.defs[group].clause, ALL_CHECKS, ["valid", "fuzz", *self.tags(canonical)],
                               frames=frames, message=canonical, compare=pins_nan(canonical))
        try:
            frame = codec.encode(self.defs, drawn["message"], drawn["encoding"])
        except EncodeError:
            return None
        mutated = self.mutate(group, frame, drawn["encoding"], drawn["mutation"], drawn["a"], drawn["b"])
        return self.frame_case(group, drawn["encoding"], mutated, drawn["mutation"])

    def frame_case(self, group: str, encoding: str, frame: bytes, mutation: str) -> dict | None:
        tags = ["fuzz", f"mutation:{mutation}"]
        spans: list = []
        try:
            decoded = codec.decode(self.defs, frame, spans)
        except NotJudged:
            return None
        except FrameError as exc:
            if self.known_elsewhere(frame, exc):
                return None
            read = [f"overrun:{exc.role}"] if exc.role else []  # errata I1/I2 are about reading ids and counts
            return self.record(group, "invalid", self.clauses[exc.rule], [f"decode-{encoding}"],
                               ["invalid", f"rule:{exc.rule}", *read, *tags], frames={encoding: frame}, rule=exc.rule)
        reasons = self.acceptable_reasons(decoded) + framing_reasons(frame, spans)
        if decoded["abbrev"] != group and decoded["abbrev"] in self.groups:  # a mutated id made it another message
            group = decoded["abbrev"]
        if reasons:
            return self.record(group, "acceptable", "imc-wire#what-real-receivers-do", [f"decode-{encoding}"],
                               ["acceptable", *reasons, *tags, *self.tags(decoded)], frames={encoding: frame},
                               message=decoded, compare=pins_nan(decoded), **acceptable_fields(reasons))
        frames = {o: frame if o == encoding else codec.encode(self.defs, decoded, o) for o in ("le", "be")}
        checks = ["decode-le", "decode-be", "roundtrip"]
        if decoded["header"]["timestamp"] == 0:  # re-encoded, a zero timestamp may be stamped (class zero-timestamp)
            return self.record(group, "acceptable", "imc-xml#header.timestamp", checks,
                               ["acceptable", "zero-timestamp", *tags, *self.tags(decoded)], frames=frames,
                               message=decoded, compare=pins_nan(decoded), **acceptable_fields(["zero-timestamp"]))
        return self.record(group, "valid", self.defs[group].clause, checks,
                           ["valid", *tags, *self.tags(decoded)], frames=frames, message=decoded,
                           compare=pins_nan(decoded))

    def ordinary(self, group: str, prop: str, case: dict) -> dict | None:
        """A message finding with the corpus's ordinary header in place of the one hypothesis shrunk it to (zeros, a
        -0.0 timestamp: properties of their own, which a promoted vector must not carry by accident)."""
        if prop != "message":
            return None
        return self.case(group, prop, dict(case["message"], header=dict(ORDINARY_HEADER)))

    def known_elsewhere(self, frame: bytes, exc: FrameError) -> bool:
        """Whether the reference refused an id that IMC.xml defines (a message beyond the seeds): a receiver of the
        whole protocol decodes it, so the frame is not judged."""
        if exc.rule not in ("unknown-id", "unknown-inline-id"):
            return False
        (mgid,) = struct.unpack_from(ORDERS[codec.byte_order_of(frame)] + "H", frame, exc.offset)
        return mgid in self.defs.ids_elsewhere

    def record(self, group: str, expect: str, clause: str, checks: list[str], tags: list[str], *,
               frames: dict[str, bytes], message: dict | None = None, compare: dict | None = None, **extra) -> dict:
        uses = used_abbrevs(self.defs, message, {group}) if message else {group}
        case = {"id": "", "expect": {self.edition: expect}, "clause": clause,
                "definitions": {a: self.defs[a].hash for a in sorted(uses) if a in self.defs.by_abbrev},
                "checks": checks, "frames": {o: f.hex() for o, f in frames.items()}}
        if message is not None:
            case["message"] = message
        if compare:
            case["compare"] = compare
        return filed(self.suite, group, case, tags, extra)

    def fields_of(self, message: dict):
        """(message definition, field, value, depth) of every field of a decoded message, inline messages and list
        elements included (iteratively: no recursion an input could drive)."""
        stack = [(message, 0)]
        while stack:
            m, depth = stack.pop()
            mdef = self.defs[m["abbrev"]]
            for f in mdef.fields:
                v = m["fields"][f.abbrev]
                yield mdef, f, v, depth
                if f.type in ("message", "message-list"):
                    stack += [(x, depth + 1) for x in (v if isinstance(v, list) else [v]) if x is not None]

    def tags(self, message: dict) -> list[str]:
        """What a decoded message holds that errata are filed by: ``nonempty:<Message>.<field>`` for each inline
        field and list that holds something, ``nested`` when inline messages nest two deep, ``non-ascii`` text,
        ``fp32-signaling-nan`` (a NaN whose quiet bit is clear in an fp32 field)."""
        out: set[str] = set()
        for mdef, f, v, depth in self.fields_of(message):
            if f.type == "plaintext" and isinstance(v, dict):
                out.add("non-ascii")
            elif f.type == "fp32_t" and isinstance(v, str) and v.startswith("nan:") and not int(v[4:], 16) & 0x400000:
                out.add("fp32-signaling-nan")
            elif f.type in ("message", "message-list") and any(x is not None for x in (v if isinstance(v, list) else [v])):
                out.add(f"nonempty:{mdef.abbrev}.{f.abbrev}")
                if depth >= 1:
                    out.add("nested")
        return sorted(out)

    def acceptable_reasons(self, message: dict) -> list[str]:
        """The implementation-defined contents of a decoded message (the corpus's acceptable classes), if any."""
        out: set[str] = set()
        for _, f, v, _ in self.fields_of(message):
            if f.enum_kind == "enum" and v not in {e.value for e in f.enum_values if e.in_edition(self.edition)}:
                out.add("out-of-table")
            elif f.enum_kind == "bitfield" and v & ~_or([e.value for e in f.enum_values]):
                out.add("undefined-bit")
            elif f.is_float and (f.minimum is not None or f.maximum is not None) and not _within(f, v):
                out.add("out-of-range")
            elif f.type == "plaintext" and isinstance(v, dict):
                out.add("non-ascii")
            elif f.type in ("message", "message-list"):
                inner = v if isinstance(v, list) else [v]
                if f.type == "message-list" and None in inner:
                    out.add("null-element")
                if f.message_types and any(x is not None and x["abbrev"] not in f.message_types for x in inner):
                    out.add("wrong-type")
        return sorted(out)

    # ------------------------------------------------------------ mutations

    def seed_frames(self, group: str) -> list[tuple[str, bytes]]:
        return self._seed_frames.get(group, [])

    def clause(self, group: str) -> str:
        return self.defs[group].clause

    def mutate(self, group: str, frame: bytes, encoding: str, mutation: str, a: int, b: int) -> bytes:
        e = ORDERS[encoding]
        n = len(frame)
        if mutation == "bit-flip":
            out = bytearray(frame)
            out[a % n] ^= 1 << (b % 8)
            return bytes(out)
        if mutation == "truncate":
            return frame[:a % n]
        if mutation == "extend":
            return frame + bytes([a & 0xFF]) * (1 + b % 8)
        if mutation == "sync":
            bad = a & 0xFFFF
            if bad in (0x54FE, 0xFE54):
                bad ^= 0x0100
            return struct.pack(">H", bad) + frame[2:]
        if mutation == "crc":
            (stored,) = struct.unpack_from(e + "H", frame, n - FOOTER_SIZE)
            return frame[:-FOOTER_SIZE] + struct.pack(e + "H", stored ^ (1 + b % 0xFFFF))
        body = bytearray(frame[:-FOOTER_SIZE])
        if mutation == "size-past-data":
            (size,) = struct.unpack_from(e + "H", body, 4)
            struct.pack_into(e + "H", body, 4, min(0xFFFF, size + 1 + b % 16))
        elif mutation == "id-neighbour":
            (mgid,) = struct.unpack_from(e + "H", body, 2)
            struct.pack_into(e + "H", body, 2, (mgid + (1 if b % 2 else -1) * (1 + a % 2)) & 0xFFFF)
        elif mutation == "payload-byte":
            if len(body) == HEADER_SIZE:
                return frame
            body[HEADER_SIZE + a % (len(body) - HEADER_SIZE)] = b & 0xFF
        else:  # a length, count or inline id pushed past what follows it
            role = "id" if mutation == "inline-id-neighbour" else None
            spans = [s for s in codec.layout(self.defs, frame)
                     if (s.role == "id" if role else s.role in ("length", "count"))]
            if not spans:
                return frame
            s = spans[a % len(spans)]
            (value,) = struct.unpack_from(e + "H", body, s.start)
            step = (1 if b % 2 else -1) * (1 + b % 3) if role else 1 + b % 8
            struct.pack_into(e + "H", body, s.start, (value + step) & 0xFFFF)
        return bytes(body) + struct.pack(e + "H", crc16(bytes(body)))


def acceptable_fields(reasons: list[str]) -> dict:
    """The class (or classes) of an acceptable generated case, the outcomes they permit and the reference's."""
    names = list(dict.fromkeys(CLASSES[r] for r in reasons))
    permitted = list(dict.fromkeys(o["outcome"] for n in names for o in outcomes(n)))
    return {"class": names[0] if len(names) == 1 else names, "outcomes": [{"outcome": o} for o in permitted],
            "reference": "accept" if all(classes()[n]["reference"] == "accept" for n in names) else "reject"}


def framing_reasons(frame: bytes, spans) -> list[str]:
    """Bytes after the footer, or payload bytes after the last field: both implementation-defined."""
    size = next(s for s in spans if s.path == "header.size")
    (declared,) = struct.unpack_from(ORDERS[codec.byte_order_of(frame)] + "H", frame, size.start)
    out = []
    if len(frame) > HEADER_SIZE + declared + FOOTER_SIZE:
        out.append("trailing-bytes")
    last = max((s.end for s in spans if s.role != "footer"), default=HEADER_SIZE)
    if last < HEADER_SIZE + declared:
        out.append("unused-payload")
    return out


def _or(values) -> int:
    out = 0
    for v in values:
        out |= v
    return out


def _within(f: FieldDef, v) -> bool:
    if isinstance(v, str):
        return False
    return (f.minimum is None or v >= f.minimum) and (f.maximum is None or v <= f.maximum)

