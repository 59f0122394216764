"""The ros_acomms fuzz source: hypothesis strategies of every type of an edition from the definitions, and mutations
of ROS 1 bytes. No per-type code: strategies follow each field's builtin, array kind and nested type.

Generated messages are valid (UTF-8 strings, ``time`` nsecs below a second, ``duration`` nsecs within ±1 s), each a
``valid`` case. A mutated frame is judged by the reference: refused (``invalid``, with its rule; ``final-blob`` when
the defect lies in a string or ``uint8[]`` that ends the message), decoded to a valid message, or decoded to what the
corpus files as implementation-defined (bytes after the message, a bool byte other than 0 and 1, string bytes that
are not UTF-8): ``acceptable``. A frame whose ``time`` or ``duration`` then carries a second or more in nsecs is not
judged (the corpus's normalising outcome is defined for its own cases only).
"""

from __future__ import annotations

import struct

from hypothesis import strategies as st

from ...fuzz.source import filed, pins_nan, sized_lists
from ...kinds.vector.errors import EncodeError, FrameError
from ...kinds.vector.floats import FLOAT_CLASSES
from . import codec
from .codec import int_bounds, int_form
from .corpus.rules import outcomes
from .definitions import PRIMITIVES, Edition, FieldType
from .msgtext import md5

ENC = "ros1"
MAX_TEXT = 200
MAX_ARRAY = 6
MUTATIONS = ("bit-flip", "truncate", "extend", "length-past-data", "byte-set")
SECOND = 1_000_000_000


class RosFuzzSource:
    """Strategies and mutations for every type of one edition."""

    suite = "ros_acomms"
    mutations = MUTATIONS

    def __init__(self, view: Edition, groups: dict[str, str], clauses: dict[str, str],
                 corpus_frames: dict[str, list[tuple[str, bytes]]] | None = None):
        self.view, self.clauses = view, clauses
        self.types = {g: full for g, full in groups.items() if full in view}  # group name -> full type name
        self.groups = tuple(self.types)
        self._seed_frames = corpus_frames or {}
        self._strategies: dict[str, object] = {}
        self._md5 = {full: md5(view, view[full]) for full in self.types.values()}  # once, not per example

    # ------------------------------------------------------------ strategies

    def fields(self, full: str):
        if full not in self._strategies:
            self._strategies[full] = st.fixed_dictionaries({f.name: self.value(f.type) for f in self.view[full].fields})
        return self._strategies[full]

    def value(self, t: FieldType):
        if t.array is not None:
            if t.base == "uint8":
                sized = st.binary(min_size=t.array, max_size=t.array) if t.array >= 0 else st.binary(max_size=MAX_TEXT)
                return sized.map(bytes.hex)
            element = self.value(t.element)
            return (st.lists(element, min_size=t.array, max_size=t.array) if t.array >= 0
                    else sized_lists(element, MAX_ARRAY))
        base = t.base
        if base == "bool":
            return st.booleans()
        if base in ("float32", "float64"):
            width = PRIMITIVES[base][1]
            specials = [v[0 if width == 4 else 1] for v in FLOAT_CLASSES.values()]
            return st.one_of(st.floats(width=width * 8, allow_nan=False), st.floats(-1e6, 1e6, width=width * 8),
                             st.sampled_from(specials))
        if base in PRIMITIVES:
            lo, hi = int_bounds(base)
            return st.one_of(st.integers(lo, hi), st.sampled_from(sorted({lo, hi, 0, 1}))).map(int_form)
        if base == "string":
            return st.text(max_size=MAX_TEXT)
        if base == "time":
            return st.fixed_dictionaries({"secs": st.integers(0, 0xFFFFFFFF), "nsecs": st.integers(0, SECOND - 1)})
        if base == "duration":
            return st.fixed_dictionaries({"secs": st.integers(-(1 << 31), (1 << 31) - 1),
                                          "nsecs": st.integers(-(SECOND - 1), SECOND - 1)})
        return st.deferred(lambda: self.fields(base))

    def message(self, group: str):
        full = self.types[group]
        return st.fixed_dictionaries({"type": st.just(full), "fields": self.fields(full)})

    def inputs(self, group: str, prop: str):
        if prop == "message":
            return self.message(group)
        return st.fixed_dictionaries({"message": self.message(group), "encoding": st.just(ENC),
                                      "mutation": st.sampled_from(MUTATIONS),
                                      "a": st.integers(0, 1 << 16), "b": st.integers(0, 1 << 16)})

    # ------------------------------------------------------------ cases

    def case(self, group: str, prop: str, drawn) -> dict | None:
        if prop == "message":
            try:
                frame = codec.encode(self.view, drawn)
            except EncodeError:
                return None
            canonical = codec.decode(self.view, drawn["type"], frame)
            return self.record(group, "valid", self.view[drawn["type"]].definition.clause,
                               [f"encode-{ENC}", f"decode-{ENC}", "roundtrip"], ["valid", "fuzz", *self.tags(canonical)],
                               frame, canonical)
        try:
            frame = codec.encode(self.view, drawn["message"])
        except EncodeError:
            return None
        mutated = self.mutate(group, frame, ENC, drawn["mutation"], drawn["a"], drawn["b"])
        return self.frame_case(group, ENC, mutated, drawn["mutation"])

    def frame_case(self, group: str, encoding: str, frame: bytes, mutation: str) -> dict | None:
        full = self.types[group]
        tags = ["fuzz", f"mutation:{mutation}"]
        spans: list = []
        try:
            decoded = codec.decode(self.view, full, frame, spans)
        except FrameError as exc:
            return self.record(group, "invalid", self.clauses[exc.rule], [f"decode-{ENC}"],
                               ["invalid", f"rule:{exc.rule}", *tags, *self.final_blob(group, frame, exc),
                                *huge_count(frame, exc)], frame, rule=exc.rule)
        if _nsecs_over(decoded):
            return None
        used = max((s.end for s in spans), default=0)
        reasons = (["trailing-bytes"] if used < len(frame) else []) + [
            "bool-byte" for s in spans if s.type == "bool" and frame[s.start] > 1][:1]
        if any(isinstance(v, dict) and set(v) == {"hex"} for v in _values(decoded)):
            reasons.append("non-utf8")
        if reasons:
            permitted = list(dict.fromkeys(o["outcome"] for r in reasons for o in outcomes(r)))
            return self.record(group, "acceptable", "ros-acomms#ros-1-serialization", [f"decode-{ENC}"],
                               ["acceptable", *reasons, *tags, *self.tags(decoded)], frame, decoded,
                               outcomes=[{"outcome": o} for o in permitted], reference="accept",
                               **{"class": reasons[0] if len(reasons) == 1 else reasons})
        return self.record(group, "valid", self.view[full].definition.clause, [f"decode-{ENC}", "roundtrip"],
                           ["valid", *tags, *self.tags(decoded)], frame, decoded)

    def final_blob(self, group: str, frame: bytes, exc: FrameError) -> list[str]:
        """``final-blob`` when the refused defect is a string or ``uint8[]`` length past the end that is the last
        thing the type reads (what genpy slices unchecked, erratum G1): with that length cut to the bytes left, the
        frame decodes."""
        if exc.rule not in ("length-overrun", "truncated"):
            return []
        prefix = exc.offset if exc.rule == "length-overrun" else exc.offset - 4
        if prefix < 0 or prefix + 4 > len(frame):
            return []
        clamped = bytearray(frame)
        struct.pack_into("<I", clamped, prefix, len(frame) - prefix - 4)
        try:
            codec.decode(self.view, self.types[group], bytes(clamped))
        except FrameError:
            return []
        return ["final-blob"]

    def record(self, group: str, expect: str, clause: str, checks: list[str], tags: list[str], frame: bytes,
               message: dict | None = None, **extra) -> dict:
        full = self.types[group]
        case = {"id": "", "expect": {self.view.name: expect}, "clause": clause, "type": full,
                "md5": self._md5[full], "checks": checks, "frames": {ENC: frame.hex()}}
        if message is not None:
            case["message"] = message
            compare = pins_nan(message)
            if compare:
                case["compare"] = compare
        return filed(self.suite, group, case, tags, extra)

    def tags(self, message: dict) -> list[str]:
        """What a decoded message holds that errata are filed by: ``time-secs-from-2^31`` (a ``time`` whose secs do
        not fit a signed 32-bit integer), ``float32-signaling-nan`` (a NaN whose quiet bit is clear: only a float32
        can hold the 8-hex-digit form)."""
        out = set()
        for value in _values(message):
            if isinstance(value, str) and value.startswith("nan:") and len(value) == 12 and not int(value[4:], 16) & 0x400000:
                out.add("float32-signaling-nan")
            elif isinstance(value, dict) and set(value) == {"secs", "nsecs"} and isinstance(value["secs"], int) \
                    and value["secs"] >= 1 << 31:
                out.add("time-secs-from-2^31")
        return sorted(out)

    # ------------------------------------------------------------ mutations

    def seed_frames(self, group: str) -> list[tuple[str, bytes]]:
        return self._seed_frames.get(group, [])

    def clause(self, group: str) -> str:
        return self.view[self.types[group]].definition.clause

    def mutate(self, group: str, frame: bytes, encoding: str, mutation: str, a: int, b: int) -> bytes:
        n = len(frame)
        if mutation == "truncate":
            return frame[:a % n] if n else frame
        if mutation == "extend":
            return frame + bytes([a & 0xFF]) * (1 + b % 8)
        if not n:
            return frame
        out = bytearray(frame)
        if mutation == "bit-flip":
            out[a % n] ^= 1 << (b % 8)
        elif mutation == "byte-set":
            out[a % n] = b & 0xFF
        else:  # length-past-data: a length or count prefix grown past the bytes that follow
            prefixes = [s for s in codec.layout(self.view, self.types[group], frame) if s.role == "length"]
            if not prefixes:
                return frame
            s = prefixes[a % len(prefixes)]
            (value,) = struct.unpack_from("<I", out, s.start)
            struct.pack_into("<I", out, s.start, (value + 1 + b % 8) & 0xFFFFFFFF)
        return bytes(out)


def _values(message: dict):
    """Every value a decoded message holds, nested ones and array elements included (iteratively)."""
    stack = [message["fields"]]
    while stack:
        value = stack.pop()
        yield value
        if isinstance(value, dict):
            stack += list(value.values())
        elif isinstance(value, list):
            stack += value


def _nsecs_over(message: dict) -> bool:
    """Whether a decoded message holds a ``time`` or ``duration`` with a second or more in nsecs."""
    return any(isinstance(v, dict) and set(v) == {"secs", "nsecs"} and isinstance(v["nsecs"], int)
               and abs(v["nsecs"]) >= SECOND for v in _values(message))


HUGE_COUNT = 1 << 24  # elements: a reader that allocates them before reading needs hundreds of MB to GBs


def huge_count(frame: bytes, exc: FrameError) -> list[str]:
    """``huge-count`` when the refused defect is a length of at least 2^24 elements past the data (what roscpp
    allocates before it reads, erratum C1)."""
    if exc.rule != "length-overrun" or exc.offset + 4 > len(frame):
        return []
    return ["huge-count"] if struct.unpack_from("<I", frame, exc.offset)[0] >= HUGE_COUNT else []
