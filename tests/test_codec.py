"""The reference codec: CRC, round trips in both byte orders, typed errors with offsets, size limits."""

from __future__ import annotations

import struct

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from imc_conformance.suites.imc import codec
from imc_conformance.suites.imc.crc16 import crc16
from imc_conformance.suites.imc.definitions import load_definitions
from imc_conformance.kinds.vector.floats import float_from_bits, float_to_bits, shortest_float

DEFS = load_definitions()


def test_crc16_arc_check_value():
    assert crc16(b"123456789") == 0xBB3D
    frame = codec.encode(DEFS, {"abbrev": "Heartbeat", "header": {}, "fields": {}}, "le")
    assert crc16(frame) == 0  # a little-endian frame's CRC over itself, footer included, is 0


def field_value(f, depth):
    if f.is_float:
        bits = st.integers(0, (1 << (8 * f.size)) - 1)
        return bits.map(lambda b: float_from_bits(b, f.size))
    if f.is_int:
        lo, hi = f.int_bounds
        return st.integers(lo, hi)
    if f.type == "plaintext":
        return st.one_of(st.text(st.characters(max_codepoint=127), max_size=20), st.binary(max_size=20).map(lambda b: {"hex": b.hex()} if not b.isascii() else b.decode()))
    if f.type == "rawdata":
        return st.binary(max_size=40).map(bytes.hex)
    inner = st.none() if depth > 1 else st.one_of(st.none(), st.sampled_from(DEFS.suite_messages).flatmap(lambda m: inline(m, depth + 1)))
    return inner if f.type == "message" else st.lists(inner.filter(lambda v: v is not None), max_size=3)


def inline(mdef, depth):
    return st.fixed_dictionaries({f.abbrev: field_value(f, depth) for f in mdef.fields}).map(lambda fs: {"abbrev": mdef.abbrev, "fields": fs})


header = st.fixed_dictionaries({"timestamp": st.integers(0, (1 << 64) - 1).map(lambda b: float_from_bits(b, 8)),
                                "src": st.integers(0, 0xFFFF), "src_ent": st.integers(0, 0xFF),
                                "dst": st.integers(0, 0xFFFF), "dst_ent": st.integers(0, 0xFF)})
messages = st.sampled_from(DEFS.messages).flatmap(
    lambda m: st.tuples(header, inline(m, 0)).map(lambda t: {"abbrev": t[1]["abbrev"], "header": t[0], "fields": t[1]["fields"]}))


@settings(max_examples=300, deadline=None)
@given(messages, st.sampled_from(["le", "be"]))
def test_round_trip_in_both_byte_orders(message, order):
    frame = codec.encode(DEFS, message, order)
    assert frame[:2] == (b"\x54\xfe" if order == "le" else b"\xfe\x54")
    assert codec.decode(DEFS, frame) == message
    other = codec.encode(DEFS, message, "be" if order == "le" else "le")
    assert len(other) == len(frame) and codec.decode(DEFS, other) == message


@settings(max_examples=500, deadline=None)
@given(st.binary(max_size=80))
def test_decoding_garbage_only_raises_frame_errors(data):
    try:
        codec.decode(DEFS, data)
    except codec.FrameError as exc:
        assert 0 <= exc.offset <= max(len(data), 20)


@settings(max_examples=200, deadline=None)
@given(messages, st.data())
def test_any_single_bit_flip_is_caught_or_decodes_consistently(message, data):
    frame = bytearray(codec.encode(DEFS, message, "le"))
    bit = data.draw(st.integers(0, 8 * len(frame) - 1))
    frame[bit // 8] ^= 1 << (bit % 8)
    with pytest.raises(codec.FrameError):
        codec.decode(DEFS, bytes(frame))  # CRC-16 catches every single-bit error


def test_errors_carry_rule_and_offset():
    frame = codec.encode(DEFS, {"abbrev": "LblRange", "header": {}, "fields": {"id": 2, "range": 152.25}}, "le")
    cases = {
        frame[:10]: ("header-truncated", 10),
        b"\x55" + frame[1:]: ("sync", 0),
        frame[:-1]: ("size-exceeds-data", len(frame) - 1),
        frame[:-1] + bytes([frame[-1] ^ 1]): ("crc", 25),
    }
    for data, (rule, offset) in cases.items():
        with pytest.raises(codec.FrameError) as err:
            codec.decode(DEFS, data)
        assert (err.value.rule, err.value.offset) == (rule, offset)


def test_encoder_writes_any_payload_a_u16_size_carries_and_holds_dunes_cap_only_when_asked():
    """65,535 payload bytes is what the size field carries (a 65,557-byte frame); DUNE's 65,535-byte frame cap is a
    rule of practice (size-limit), held only when asked; a longer text has no u16 length (payload-overflow)."""
    ok = {"abbrev": "TextMessage", "header": {}, "fields": {"origin": "", "text": "x" * 65509}}
    assert len(codec.encode(DEFS, ok, "le")) == 65535
    over_cap = dict(ok, fields={"origin": "", "text": "x" * 65510})
    assert len(codec.encode(DEFS, over_cap, "le")) == 65536
    with pytest.raises(codec.EncodeError) as err:
        codec.encode(DEFS, over_cap, "le", held=frozenset({"size-limit"}))
    assert err.value.rule == "size-limit"
    largest = dict(ok, fields={"origin": "", "text": "x" * 65531})  # 2 + 2 + 65,531 = 65,535 payload bytes
    assert len(codec.encode(DEFS, largest, "le")) == 65557
    for fields in ({"origin": "", "text": "x" * 65532}, {"origin": "", "text": "x" * 65536}):
        with pytest.raises(codec.EncodeError) as err:
            codec.encode(DEFS, dict(ok, fields=fields), "le")
        assert err.value.rule == "payload-overflow"


def test_every_rule_switched_off_is_what_a_reader_without_it_does():
    """The codec's switches (the oracle's and the per-rule mutants'): a frame cut short is refused for
    size-exceeds-data, then, with that off, for its CRC, and with both off it decodes with its missing field empty."""
    frame = codec.encode(DEFS, {"abbrev": "LblRange", "header": {}, "fields": {"id": 2, "range": 152.25}}, "le")
    cut = frame[:23]  # header, id, and two bytes of range, which the CRC check then takes for the footer
    refusals = []
    off = frozenset()
    while True:
        try:
            decoded = codec.decode(DEFS, cut, off=off)
            break
        except codec.FrameError as exc:
            refusals.append(exc.rule)
            off |= {exc.rule}
    assert refusals == ["size-exceeds-data", "crc", "field-overrun"]
    assert decoded["fields"] == {"id": 2, "range": 0.0}
    assert set(codec.LENIENT) >= set(refusals)


def test_encoder_refuses_values_outside_the_field_type():
    msg = {"abbrev": "AcousticStatus", "header": {}, "fields": {"req_id": 1, "type": 0, "status": 666, "info": "", "range": 0.0}}
    with pytest.raises(codec.EncodeError) as err:
        codec.encode(DEFS, msg, "le")
    assert err.value.rule == "value-out-of-type"


def test_layout_names_every_byte():
    msg = {"abbrev": "AcousticOperation", "header": {}, "fields": {"op": 11, "system": "b1", "range": 0.0,
                                                                  "msg": {"abbrev": "LblRange", "fields": {"id": 1, "range": 10.5}}}}
    frame = codec.encode(DEFS, msg, "le")
    spans = codec.layout(DEFS, frame)
    covered = sorted(i for s in spans for i in range(s.start, s.end))
    assert covered == list(range(len(frame)))
    assert [s.path for s in spans if s.start == 32] == ["AcousticOperation.msg.LblRange.range"]


@pytest.mark.parametrize("value,width,bits", [
    (-0.0, 4, 0x80000000), ("nan", 4, 0x7FC00000), ("nan:7fc00001", 4, 0x7FC00001), ("-inf", 8, 0xFFF0000000000000),
    (152.25, 4, 0x43184000), (0.1, 4, 0x3DCCCCCD)])
def test_float_values_and_bits(value, width, bits):
    assert float_to_bits(value, width) == bits
    assert float_to_bits(float_from_bits(bits, width), width) == bits


def test_fp32_values_are_written_as_the_shortest_round_trip_decimal():
    f = struct.unpack("<f", struct.pack("<f", 0.1))[0]
    assert repr(shortest_float(f, 4)) == "0.1"
    assert repr(float_from_bits(0x00000001, 4)) == "1e-45"
    assert repr(float_from_bits(0x7F7FFFFF, 4)) == "3.4028235e+38"


def _both_ways(frame: bytes):
    """What the precompiled unpackers decode ``frame`` to and what the field-by-field reader does (asked for the
    byte map, the codec takes the reader): a message, or the error's rule, offset and detail."""
    out = []
    for spans in (None, []):
        try:
            out.append(codec.decode(DEFS, frame, spans))
        except (codec.FrameError, codec.NotJudged) as exc:
            out.append((type(exc).__name__, exc.rule if hasattr(exc, "rule") else exc.reason, exc.offset, exc.detail))
    return out


def test_the_unpackers_decode_every_corpus_frame_as_the_reader_does(records):
    seen = 0
    for c in records:
        for frame in c.get("frames", {}).values():
            fast, slow = _both_ways(bytes.fromhex(frame))
            assert fast == slow, c["id"]
            seen += 1
    assert seen > 4000  # both byte orders of every case that has frames


@settings(max_examples=300, deadline=None)
@given(messages, st.sampled_from(["le", "be"]), st.data())
def test_the_unpackers_agree_with_the_reader_on_damaged_frames(message, order, data):
    frame = bytearray(codec.encode(DEFS, message, order))
    cut = data.draw(st.integers(codec.HEADER_SIZE, len(frame)))
    body = frame[:cut]
    if len(body) > codec.HEADER_SIZE and data.draw(st.booleans()):
        i = data.draw(st.integers(codec.HEADER_SIZE, len(body) - 1))
        body[i] = data.draw(st.integers(0, 255))
    size = len(body) - codec.HEADER_SIZE  # the size and CRC made right again, so the fields are what is read
    struct.pack_into(("<" if order == "le" else ">") + "H", body, 4, size)
    body += struct.pack(("<" if order == "le" else ">") + "H", crc16(bytes(body)))
    fast, slow = _both_ways(bytes(body))
    assert fast == slow
