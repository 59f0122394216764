"""Invalid vectors: one broken rule each, in both byte orders, labelled with the rule id.

Where DUNE would read a missing u16 prefix out of the bytes after the payload (the CRC), the
generator keeps those bytes outside IMC's id space (never FF FF, never an id IMC.xml assigns),
so that a DUNE-like receiver does not accept the frame by accident (imcpy erratum I1).

Every overrun and truncation is also followed by more bytes (a second, valid frame, as in a stream or a log; for a
truncation, also a CRC-correct footer after the cut), so that a reader that reads past ``size`` finds bytes to read
and is caught, instead of running out of data. A CRC case changes only bytes that nothing but the CRC can see. The
rules each case breaks are the oracle's (``oracle.flaws``): a case breaking more than its rule lists them, with why.
"""

from __future__ import annotations

import copy

from .. import codec
from ..codec import HEADER_SIZE
from ..crc16 import crc16
from . import samples
from .coverage import load_rules
from .records import MessageCases
from .oracle import decode_refusal, encode_refusal, flaws, practice_also_broken
from .surgery import flip, payload_of, read_u16, reframe, swapped_crc, u16, with_crc
from .valid import BASE, first_variable_field, variable_kind

UNUSED_ID = 999  # no message in IMC.xml has this id
HIGHEST_IMC_ID = 4095  # IMC.xml assigns no id above this (checked against IMC.xml by the tests)
# Why a family's cases break more rules than the one a receiver checks first (flaws.why; a family followed by a
# frame shares its family's reason).
WHY = {
    "truncated": "A frame cut short loses its footer with its payload: what a reader that skips the size check takes for "
                 "the CRC is payload, and the fields the cut removed are missing too.",
    "truncated-then-footer": "The cut payload is followed by a CRC over it, but the size field still claims the whole "
                             "payload, and the fields the cut removed are missing.",
    "truncated-then-frame": "A frame cut short and followed by another: the bytes its size claims run into the next "
                            "frame, which then neither makes the CRC nor the fields the cut removed.",
    "payload-cut": "The payload ends at one field: every field after it is missing too.",
    "length-overrun": "A length reaching past the payload's end leaves no bytes for the fields after it.",
    "list-count-overrun": "A count claiming more elements than the payload holds leaves no bytes for what follows them.",
    "unknown-inline-id": "An inline message of unknown id has no known size: the bytes after its id cannot be placed, "
                         "so the fields after it are misread.",
}


def add_invalid(mc: MessageCases) -> None:
    defs, mdef = mc.defs, mc.mdef
    clauses = load_clauses()
    base = samples.message(mdef.abbrev, samples.filled_fields(defs, mdef), samples.ORDINARY_HEADER)
    for order in ("le", "be"):
        frame = codec.encode(defs, base, order)
        spans = codec.layout(defs, frame)
        follower = frame  # the valid frame that follows a broken one in a stream

        def invalid(path, rule, broken, checks=None, message=None, **extra):
            found = flaws(defs, broken, rule)
            if len(found) > 1:
                family = path.split("/")[0]
                family = family if family in WHY else family.removesuffix("-then-frame")
                if family not in WHY:
                    raise ValueError(f"imc/{mdef.abbrev}/{path}/{order} breaks {', '.join(found)}, not only {rule}")
                extra["flaws"] = {"rules": found, "why": WHY[family]}
            practice = practice_also_broken(lambda off, held: decode_refusal(defs, broken, off, held), found, PRACTICES)
            if practice:  # a receiver holding that practice may name it (DUNE: size-limit)
                extra["practice"] = practice
            mc.add(f"{path}/{order}", expect="invalid", clause=clauses[rule], checks=checks or [f"decode-{order}"],
                   tags=["invalid", f"rule:{rule}", f"byte-order:{order}"], frames={order: broken}, rule=rule,
                   message=message, base=f"imc/{mdef.abbrev}/{BASE}", **extra)

        def followed(path, broken, **extra):
            """The broken frame, then the valid one (a stream, a log, a datagram with more after it); none where the
            bytes that follow make it whole again (a frame cut inside its CRC, whose missing byte the next frame's
            first byte happens to be)."""
            head, _, rest = path.partition("/")
            then = broken + follower
            rule = decode_refusal(defs, then)
            if rule is not None:
                invalid(f"{head}-then-frame/{rest}", rule, then, **extra)

        # sync (the CRC recomputed over the edited bytes, so that sync is the only rule broken)
        invalid("sync/first-byte", "sync", with_crc(flip(frame, 0, 0x01), order))
        invalid("sync/zero", "sync", with_crc(b"\x00\x00" + frame[2:], order))
        invalid("sync/first-byte-repeated", "sync", with_crc(frame[:1] * 2 + frame[2:], order),
                comment="Both sync bytes equal the first one (54 54 or FE FE): neither order.")
        # CRC: flipped in every region, and stored in the wrong byte order; in the payload only a value's byte,
        # never a length, count or id (a reader with no CRC check would refuse those for their own rule)
        for region, offset in (("header-timestamp", 10), ("header-src", 14), ("header-dst", 17)):
            invalid(f"crc/{region}", "crc", flip(frame, offset))
        values = [i for s in spans if s.role == "value" and s.start >= HEADER_SIZE for i in range(s.start, s.end)]
        if values:
            invalid("crc/payload", "crc", flip(frame, values[0]))
            invalid("crc/payload-last-byte", "crc", flip(frame, values[-1], 0x80))
        invalid("crc/footer-after-unsized-bytes", "crc", unsized_bytes(frame, order),
                comment="The size field stops two bytes short of where the footer is: the bytes at the size field's end "
                        "are not a CRC, and the right one sits at the end of the data, where a reader that takes the "
                        "CRC from the end of a datagram looks.")
        invalid("crc/footer-first-byte", "crc", flip(frame, len(frame) - 2))
        invalid("crc/footer-second-byte", "crc", flip(frame, len(frame) - 1, 0x80))
        palindrome_free = perturbed(mc, base, order, lambda f: f[-1] != f[-2])
        invalid("crc/wrong-byte-order", "crc", swapped_crc(palindrome_free),
                comment="The CRC is right but stored in the other byte order (never a palindromic CRC).")
        # truncation at every structural boundary (size field unchanged); past the header, also followed by a
        # CRC-correct footer over the bytes kept, and by the next frame
        for cut, name in boundaries(spans, len(frame)):
            rule = "header-truncated" if cut < HEADER_SIZE else "size-exceeds-data"
            invalid(f"truncated/{name}", rule, frame[:cut])
            if cut >= HEADER_SIZE:
                footed = frame[:cut] + u16(order, crc16(frame[:cut]))
                rule = decode_refusal(defs, footed)  # None: the footer made it whole (a cut at the payload's end)
                if rule is not None:
                    invalid(f"truncated-then-footer/{name}", rule, footed)
                followed(f"truncated/{name}", frame[:cut])
        # size field: larger than the data (the CRC is over the bytes present, so only the size is wrong)
        size = read_u16(frame, order, 4)
        for name, value in (("plus-1", size + 1), ("plus-1000", size + 1000), ("claimed-65514", defs.max_payload + 1),
                            ("claimed-65535", 0xFFFF)):
            if value <= 0xFFFF:
                invalid(f"size-exceeds-data/{name}", "size-exceeds-data", reframe(frame, order, size=value))
        # message id
        invalid(f"unknown-id/{UNUSED_ID}", "unknown-id", reframe(frame, order, mgid=UNUSED_ID))
        invalid("unknown-id/null-65535", "unknown-id", reframe(frame, order, mgid=defs.null_id))
        # payload cut at each field boundary (size and CRC consistent): the fields overrun the payload
        add_payload_cuts(mc, invalid, followed, base, order, spans)
        add_prefix_overruns(mc, invalid, followed, base, order, spans)
    add_overflow(mc)


def unsized_bytes(frame: bytes, order: str) -> bytes:
    """The frame with two more payload bytes the size field does not count, its footer over all of them."""
    body = frame[:-2] + b"\x00\x00"
    return body + u16(order, crc16(body))




def boundaries(spans, length: int):
    """(cut offset, name) for every structural boundary of a frame: 0, inside sync, after each span, inside the CRC."""
    cuts = {0: "empty", 1: "inside-header.sync"}
    for s in spans:
        if s.end < length:
            cuts.setdefault(s.end, f"after-{s.path}")
    cuts[length - 1] = "inside-footer.crc16"
    return sorted(cuts.items())


def perturbed(mc: MessageCases, message: dict, order: str, accept, build=None) -> bytes:
    """The first frame, over deterministic timestamp nudges of ``message``, that satisfies ``accept``."""
    build = build or (lambda m: codec.encode(mc.defs, m, order))
    for step in range(256):
        candidate = copy.deepcopy(message)
        candidate["header"]["timestamp"] = message["header"]["timestamp"] + step
        frame = build(candidate)
        if accept(frame):
            return frame
    raise RuntimeError(f"{mc.mdef.abbrev}: no timestamp nudge satisfies the frame constraint")


def outside_id_space(frame: bytes, order: str, offset: int) -> bool:
    """True if the u16 at ``offset`` is neither the null id (FF FF) nor an id IMC assigns."""
    value = read_u16(frame, order, offset)
    return HIGHEST_IMC_ID < value < 0xFFFF


def crc_guard(role: str, order: str, cut: int):
    """What the CRC bytes must not be when DUNE would read the missing prefix at ``cut`` out of them.

    An inline or element id must stay outside IMC's id space; a list count must not be 0 (DUNE would
    accept an empty list). Other prefixes are bounds-checked by DUNE and need no guard.
    """
    if role == "id":
        return lambda f: outside_id_space(f, order, cut)
    if role == "count":
        return lambda f: read_u16(f, order, cut) != 0
    return None


def add_payload_cuts(mc: MessageCases, invalid, followed, base: dict, order: str, spans) -> None:
    """Cut the payload (size and CRC recomputed) at each field boundary and inside each length-prefixed value."""
    payload_spans = [s for s in spans if s.role not in ("header", "footer")]
    cuts: dict[int, tuple[str, str, str | None]] = {}
    for s in payload_spans:
        rule = "length-overrun" if s.type in ("plaintext", "rawdata") else "field-overrun"
        if s.role == "id" and s.path.endswith("].id"):
            rule = "list-count-overrun"
        if s.end - s.start > 1 and s.type in ("plaintext", "rawdata"):
            cuts.setdefault(s.start + 1, (f"inside-{s.path}", rule, None))
        cuts.setdefault(s.start, (f"before-{s.path}", rule, s.role))
    for cut, (name, rule, role) in sorted(cuts.items()):

        def build(m, cut=cut):
            f = codec.encode(mc.defs, m, order)
            return reframe(f, order, payload=payload_of(f, order)[:cut - HEADER_SIZE])

        guard = crc_guard(role, order, cut) if role else None
        frame = perturbed(mc, base, order, guard or (lambda f: True), build)
        extra = {}
        if role == "id":
            extra = {"erratum": "I1", "comment": "DUNE reads this missing id out of the CRC bytes (erratum I1); they are "
                                                 "chosen so that it still rejects."}
        elif guard is not None:
            extra = {"erratum": "I2", "comment": "DUNE reads this missing count out of the CRC bytes and then element ids "
                                                 "from past the frame (erratum I2)."}
        invalid(f"payload-cut/{name}", rule, frame, **extra)
        followed(f"payload-cut/{name}", frame, **extra)


def add_prefix_overruns(mc: MessageCases, invalid, followed, base: dict, order: str, spans) -> None:
    """Length, count and inline-id prefixes that lie: past the payload, or naming an undefined message."""
    frame = codec.encode(mc.defs, base, order)
    end = len(frame) - 2
    for s in spans:
        if s.role == "length":
            data_start = s.end
            claimed = end - data_start + 1
            patched = frame[:s.start] + u16(order, claimed) + frame[s.end:]
            broken = reframe(patched, order, payload=payload_of(patched, order))
            invalid(f"length-overrun/{s.path[:-len('.length')]}", "length-overrun", broken)
            followed(f"length-overrun/{s.path[:-len('.length')]}", broken)
        elif s.role == "count":
            count = read_u16(frame, order, s.start)

            def build(m, start=s.start, count=count):
                f = codec.encode(mc.defs, m, order)
                return reframe(f[:start] + u16(order, count + 1) + f[start + 2:], order)

            list_path = s.path[:-len(".count")]
            after = max((x.end for x in spans if x.path.startswith(list_path + "[")), default=s.end)
            if after < end:  # fields follow the list: the element claimed too many is read from them (their
                continue  # bytes, not the CRC, make its id): that is another case, not generated
            guarded = perturbed(mc, base, order, lambda f, at=after: outside_id_space(f, order, at), build)
            comment = ("The count claims one element more than the payload holds; DUNE would read its id from the CRC "
                       "bytes, kept outside IMC's id space.")
            invalid(f"list-count-overrun/{list_path}", "list-count-overrun", guarded, erratum="I1", comment=comment)
            followed(f"list-count-overrun/{list_path}", guarded, erratum="I1", comment=comment)
        elif s.role == "id":
            patched = frame[:s.start] + u16(order, UNUSED_ID) + frame[s.end:]
            invalid(f"unknown-inline-id/{s.path[:-len('.id')]}", "unknown-inline-id",
                    reframe(patched, order, payload=payload_of(patched, order)))


def add_overflow(mc: MessageCases) -> None:
    """A message whose first plaintext or rawdata holds 65,536 bytes: no u16 length carries it, encoders must refuse.
    Made from the valid case whose field fills the payload exactly (its base): the same fields, the text made longer."""
    f = first_variable_field(mc)
    if f is None:
        return
    value = "x" * 0x10000 if f.type == "plaintext" else "a5" * 0x10000
    message = samples.with_field(samples.message(mc.mdef.abbrev, samples.default_fields(mc.mdef), samples.ORDINARY_HEADER),
                                 f.abbrev, value)
    practice = practice_also_broken(lambda off, held: encode_refusal(mc.defs, message, "le", off, held),
                                    ["payload-overflow"], PRACTICES)
    mc.add(f"payload-overflow/{f.abbrev}-65536", expect="invalid", clause=load_clauses()["payload-overflow"],
           checks=["encode-le", "encode-be"], tags=["invalid", "rule:payload-overflow", f"field:{f.abbrev}"],
           message=message, rule="payload-overflow", practice=practice,
           base=f"imc/{mc.mdef.abbrev}/{variable_kind(f)}/{f.abbrev}/max-payload",
           comment="65,536 bytes of text: neither its u16 length nor the payload's u16 size can carry it.")


def load_clauses() -> dict[str, str]:
    return {r["id"]: r["clause"] for r in load_rules()}


PRACTICES = frozenset(r["id"] for r in load_rules() if r["level"] == "practice")
