"""Invalid vectors: one broken rule each, in both byte orders, labelled with the rule id.

Where DUNE would read a missing u16 prefix out of the bytes after the payload (the CRC), the
generator keeps those bytes outside IMC's id space (never FF FF, never an id IMC.xml assigns),
so that a DUNE-like receiver does not accept the frame by accident (imcpy erratum I1).
"""

from __future__ import annotations

import copy

from .. import codec
from ..codec import HEADER_SIZE
from . import samples
from .coverage import load_rules
from .records import MessageCases
from .surgery import flip, payload_of, read_u16, reframe, swapped_crc, u16, with_crc
from .valid import first_variable_field, max_fill

UNUSED_ID = 999  # no message in IMC.xml has this id
HIGHEST_IMC_ID = 4095  # IMC.xml assigns no id above this (checked against IMC.xml by the tests)


def add_invalid(mc: MessageCases) -> None:
    defs, mdef = mc.defs, mc.mdef
    clauses = {r["id"]: r["clause"] for r in load_rules()}
    base = samples.message(mdef.abbrev, samples.filled_fields(defs, mdef),
                           {"timestamp": 1700000000.5, "src": 0x001E, "src_ent": 42, "dst": 0x4101, "dst_ent": 7})
    for order in ("le", "be"):
        frame = codec.encode(defs, base, order)
        spans = codec.layout(defs, frame)

        def invalid(path, rule, broken, checks=None, message=None, **extra):
            mc.add(f"{path}/{order}", expect="invalid", clause=clauses[rule], checks=checks or [f"decode-{order}"],
                   tags=["invalid", f"rule:{rule}", f"byte-order:{order}"], frames={order: broken}, rule=rule,
                   message=message, **extra)

        # sync (the CRC recomputed over the edited bytes, so that sync is the only rule broken)
        invalid("sync/first-byte", "sync", with_crc(flip(frame, 0, 0x01), order))
        invalid("sync/zero", "sync", with_crc(b"\x00\x00" + frame[2:], order))
        invalid("sync/first-byte-repeated", "sync", with_crc(frame[:1] * 2 + frame[2:], order),
                comment="Both sync bytes equal the first one (54 54 or FE FE): neither order.")
        # CRC: flipped in every region, and stored in the wrong byte order
        for region, offset in (("header-timestamp", 10), ("header-src", 14), ("header-dst", 17)):
            invalid(f"crc/{region}", "crc", flip(frame, offset))
        if len(frame) > HEADER_SIZE + 2:
            invalid("crc/payload", "crc", flip(frame, HEADER_SIZE))
            invalid("crc/payload-last-byte", "crc", flip(frame, len(frame) - 3, 0x80))
        invalid("crc/footer-first-byte", "crc", flip(frame, len(frame) - 2))
        invalid("crc/footer-second-byte", "crc", flip(frame, len(frame) - 1, 0x80))
        palindrome_free = perturbed(mc, base, order, lambda f: f[-1] != f[-2])
        invalid("crc/wrong-byte-order", "crc", swapped_crc(palindrome_free),
                comment="The CRC is right but stored in the other byte order (never a palindromic CRC).")
        # truncation at every structural boundary (size field unchanged)
        for cut, name in boundaries(spans, len(frame)):
            rule = "header-truncated" if cut < HEADER_SIZE else "size-exceeds-data"
            invalid(f"truncated/{name}", rule, frame[:cut])
        # size field
        size = read_u16(frame, order, 4)
        # a size field larger than the data; the CRC is over the bytes present, so only the size is wrong
        for name, delta in (("plus-1", 1), ("plus-1000", 1000)):
            if size + delta <= defs.max_payload:
                invalid(f"size-exceeds-data/{name}", "size-exceeds-data", reframe(frame, order, size=size + delta))
        invalid("size-limit/claimed-65514", "size-limit", reframe(frame, order, size=defs.max_payload + 1))
        invalid("size-limit/claimed-65535", "size-limit", reframe(frame, order, size=0xFFFF))
        add_oversize(mc, invalid, order)
        # message id
        invalid(f"unknown-id/{UNUSED_ID}", "unknown-id", reframe(frame, order, mgid=UNUSED_ID))
        invalid("unknown-id/null-65535", "unknown-id", reframe(frame, order, mgid=defs.null_id))
        # payload cut at each field boundary (size and CRC consistent): the fields overrun the payload
        add_payload_cuts(mc, invalid, base, order, spans)
        add_prefix_overruns(mc, invalid, base, order, spans)




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


def add_payload_cuts(mc: MessageCases, invalid, base: dict, order: str, spans) -> None:
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
        if guard is None:
            invalid(f"payload-cut/{name}", rule, frame)
        elif role == "id":
            invalid(f"payload-cut/{name}", rule, frame, erratum="I1",
                    comment="DUNE reads this missing id out of the CRC bytes (erratum I1); they are chosen so that it still rejects.")
        else:
            invalid(f"payload-cut/{name}", rule, frame, erratum="I2",
                    comment="DUNE reads this missing count out of the CRC bytes and then element ids from past the frame (erratum I2).")


def add_prefix_overruns(mc: MessageCases, invalid, base: dict, order: str, spans) -> None:
    """Length, count and inline-id prefixes that lie: past the payload, or naming an undefined message."""
    frame = codec.encode(mc.defs, base, order)
    end = len(frame) - 2
    for s in spans:
        if s.role == "length":
            data_start = s.end
            claimed = end - data_start + 1
            patched = frame[:s.start] + u16(order, claimed) + frame[s.end:]
            invalid(f"length-overrun/{s.path[:-len('.length')]}", "length-overrun",
                    reframe(patched, order, payload=payload_of(patched, order)))
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
            invalid(f"list-count-overrun/{list_path}", "list-count-overrun", guarded, erratum="I1",
                    comment="The count claims one element more than the payload holds; DUNE would read its id from the CRC bytes, kept outside IMC's id space.")
        elif s.role == "id":
            patched = frame[:s.start] + u16(order, UNUSED_ID) + frame[s.end:]
            invalid(f"unknown-inline-id/{s.path[:-len('.id')]}", "unknown-inline-id",
                    reframe(patched, order, payload=payload_of(patched, order)))


def add_oversize(mc: MessageCases, invalid, order: str) -> None:
    """A real frame one byte over the limit: decoders must reject it and encoders must refuse the message."""
    f = first_variable_field(mc)
    if f is None:
        return
    fill = max_fill(mc, f, extra=1)
    value = "x" * fill if f.type == "plaintext" else "a5" * fill
    message = samples.with_field(samples.message(mc.mdef.abbrev, samples.default_fields(mc.mdef)), f.abbrev, value)
    payload = codec.encode_payload(mc.defs, mc.mdef, message["fields"], codec.ORDERS[order])
    head = codec.encode(mc.defs, samples.message(mc.mdef.abbrev, samples.default_fields(mc.mdef)), order)
    frame = reframe(head, order, payload=payload)
    invalid(f"size-limit/actual-65514-{f.abbrev}", "size-limit", frame, checks=[f"encode-{order}", f"decode-{order}"],
            message=message, comment="A 65536-byte frame: the payload is one byte over 65513.")
