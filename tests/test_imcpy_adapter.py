"""The imcpy adapter against the reference codec, and its translation of imcpy's refusals."""

from __future__ import annotations

import imcpy
import pytest

from imc_conformance.suites.imc import codec
from imc_conformance.adapter_api import Rejected, Unsupported
from imc_conformance.adapters.imcpy_adapter import ImcpyAdapter, adapter
from imc_conformance.suites.imc.crc16 import crc16
from imc_conformance.suites.imc.definitions import load_definitions
from imc_conformance.suites.imc.whole import imc_xml_definitions

DEFS = load_definitions()
HEADER = {"timestamp": 1700000000.5, "src": 30, "src_ent": 42, "dst": 0x1234, "dst_ent": 7}
INLINE_KINDS = ("message", "message-list")
# A message without inline fields, for inline fields that accept any message.
LEAF = next(m.abbrev for m in DEFS.messages if m.fields and all(f.type not in INLINE_KINDS for f in m.fields))


@pytest.fixture(scope="module")
def imc() -> ImcpyAdapter:
    return adapter()


def sample_fields(abbrev: str, depth: int = 0) -> dict:
    """Non-default values for every field of ``abbrev``; inline fields nest down to depth 2."""
    fields = {}
    for i, f in enumerate(DEFS[abbrev].fields, start=1):
        if f.is_int:
            lo, hi = f.int_bounds
            fields[f.abbrev] = hi - i if lo == 0 else lo + i
        elif f.type == "fp32_t":
            fields[f.abbrev] = -1.25 * i
        elif f.type == "fp64_t":
            fields[f.abbrev] = 41.123456789012 * i
        elif f.type == "plaintext":
            fields[f.abbrev] = f"{abbrev}.{f.abbrev}"
        elif f.type == "rawdata":
            fields[f.abbrev] = "00ff" + f"{i:02x}"
        else:
            types = f.message_types or (LEAF,)
            if f.type == "message":
                fields[f.abbrev] = sample_inline(types[0], depth)
            else:
                fields[f.abbrev] = [] if depth >= 2 else [sample_inline(types[k % len(types)], depth) for k in range(2)]
    return fields


def sample_inline(abbrev: str, depth: int):
    return None if depth >= 2 else {"abbrev": abbrev, "fields": sample_fields(abbrev, depth + 1)}


def sample(abbrev: str) -> dict:
    return {"abbrev": abbrev, "header": dict(HEADER), "fields": sample_fields(abbrev)}


def test_hello(imc):
    assert imc.hello() == {"implementation": "imcpy 1.1.2 (DUNE C++ codec, IMC 5.4.30)",
                           "suites": ["imc"], "byte_orders": ["le"], "errata": "imcpy"}


@pytest.mark.parametrize("abbrev", [m.abbrev for m in DEFS.messages])
def test_every_message_matches_the_reference_codec(imc, abbrev):
    message = sample(abbrev)
    assert imc.encode("imc", message, "le") == codec.encode(DEFS, message, "le")
    big_endian = codec.encode(DEFS, message, "be")
    assert imc.decode("imc", big_endian) == codec.decode(DEFS, big_endian) == message


def test_the_sample_nests_messages():
    assert sample("AcousticOperation")["fields"]["msg"]["abbrev"] == LEAF
    data = sample("HistoricData")["fields"]["data"]
    assert [d["abbrev"] for d in data] == ["RemoteCommand", "HistoricSample"]


def test_missing_header_keys_take_the_defaults(imc):
    message = {"abbrev": "LblRange", "fields": {"id": 2, "range": 152.25}}
    assert imc.encode("imc", message, "le") == codec.encode(DEFS, message, "le")


def test_special_floats_round_trip(imc):
    message = {"abbrev": "LblBeacon", "header": dict(HEADER), "fields": dict(
        sample_fields("LblBeacon"), lat="nan:7ff8000000000001", lon="-inf", depth="nan:7fc00001")}
    frame = imc.encode("imc", message, "le")
    assert frame == codec.encode(DEFS, message, "le")
    assert imc.decode("imc", frame) == message


def test_unsupported_byte_order_and_suite(imc):
    with pytest.raises(Unsupported):
        imc.encode("imc", sample("LblRange"), "be")
    with pytest.raises(Unsupported):
        imc.encode("other", sample("LblRange"), "le")
    with pytest.raises(Unsupported):
        imc.decode("other", codec.encode(DEFS, sample("LblRange")))


@pytest.mark.parametrize("corrupt, rule", [
    (lambda f: f[:-1] + bytes([f[-1] ^ 0x01]), "crc"),
    (lambda f: b"\x00" + f[1:], "sync"),
    (lambda f: f[:-3], None),
    (lambda f: f[:10], None),
])
def test_broken_frames_are_rejected(imc, corrupt, rule):
    with pytest.raises(Rejected) as caught:
        imc.decode("imc", corrupt(codec.encode(DEFS, sample("LblConfig"))))
    assert caught.value.rule == rule
    assert caught.value.reason


def test_unknown_id_is_rejected_without_a_rule(imc):
    frame = codec.encode(DEFS, sample("LblRange"))
    body = frame[:2] + (999).to_bytes(2, "little") + frame[4:-2]
    with pytest.raises(Rejected) as caught:
        imc.decode("imc", body + crc16(body).to_bytes(2, "little"))
    assert (caught.value.rule, caught.value.reason) == (None, "invalid message identification number: 999")


def refusal_rule(imc, message) -> str | None:
    """The rule named by imcpy's refusal to encode ``message`` (the encode must be refused)."""
    with pytest.raises(Rejected) as caught:
        imc.encode("imc", message, "le")
    return caught.value.rule


def test_value_out_of_type(imc):
    message = sample("AcousticStatus")
    message["fields"]["status"] = 666
    assert refusal_rule(imc, message) == "value-out-of-type"
    message = sample("LblRange")
    message["header"]["src"] = 0x10000
    assert refusal_rule(imc, message) == "value-out-of-type"


@pytest.mark.parametrize("field, value", [("status", 1.5), ("info", 7), ("range", "fast"), ("range", [])])
def test_value_type(imc, field, value):
    message = sample("AcousticStatus")
    message["fields"][field] = value
    assert refusal_rule(imc, message) == "value-type"


def test_unknown_field_and_message(imc):
    message = sample("LblRange")
    message["fields"]["bogus"] = 1
    assert refusal_rule(imc, message) == "unknown-field"
    assert refusal_rule(imc, {"abbrev": "NoSuchMessage", "fields": {}}) == "unknown-message"


def test_typed_inline_fields_refuse_other_messages(imc):
    message = sample("HistoricDataQuery")
    message["fields"]["data"] = {"abbrev": "LblRange", "fields": sample_fields("LblRange")}
    with pytest.raises(Rejected) as caught:
        imc.encode("imc", message, "le")
    assert caught.value.rule is None and "Failed to cast" in caught.value.reason
    message = sample("LblConfig")
    message["fields"]["beacons"][1] = {"abbrev": "LblRange", "fields": sample_fields("LblRange")}
    with pytest.raises(Rejected) as caught:
        imc.encode("imc", message, "le")
    assert caught.value.rule is None


def test_null_list_elements(imc):
    message = sample("LblConfig")
    message["fields"]["beacons"][1] = None
    assert imc.decode("imc", codec.encode(DEFS, message, "le")) == message
    with pytest.raises(Rejected) as caught:  # imcpy lists cannot hold null
        imc.encode("imc", message, "le")
    assert caught.value.rule is None


def test_null_inline_message(imc):
    message = sample("AcousticOperation")
    message["fields"]["msg"] = None
    assert imc.encode("imc", message, "le") == codec.encode(DEFS, message, "le")
    assert imc.decode("imc", codec.encode(DEFS, message, "be")) == message


def test_non_ascii_plaintext_decodes_lossily(imc):
    """imcpy's plaintext getter turns every non-ASCII byte into U+FFFD, even valid UTF-8."""
    message = {"abbrev": "TextMessage", "fields": {"origin": "é", "text": {"hex": "41ff42"}}}
    frame = imc.encode("imc", message, "le")
    assert frame == codec.encode(DEFS, message, "le")
    assert imc.decode("imc", frame)["fields"] == {"origin": "\ufffd\ufffd", "text": "A\ufffdB"}


def test_messages_beyond_the_definitions_go_through_the_imc_xml_imcpy_was_built_from(imc):
    xml = imc_xml_definitions()
    state = imcpy.EstimatedState()
    state.depth = 12.5
    decoded = imc.decode("imc", state.serialize())
    assert decoded["abbrev"] == "EstimatedState" and decoded["fields"]["depth"] == 12.5
    assert list(decoded["fields"]) == [f.abbrev for f in xml["EstimatedState"].fields]
    outer = imcpy.AcousticMessage()
    outer.message = state
    assert imc.decode("imc", outer.serialize())["fields"]["message"]["fields"]["depth"] == 12.5
    frame = imc.encode("imc", {"abbrev": "EstimatedState", "fields": {"depth": 12.5, "psi": 0.5}}, "le")
    assert (imcpy.Packet.deserialize(frame).depth, imcpy.Packet.deserialize(frame).psi) == (12.5, 0.5)


def test_boolean_fields_the_binding_cannot_read_are_unsupported_not_errors(imc):
    """Erratum I6: imcpy's getters of IMC.xml's Boolean enumeration raise TypeError; encoding works."""
    frame = imc.encode("imc", {"abbrev": "Sample", "fields": {"syringe0": 1}}, "le")
    assert codec.decode(imc_xml_definitions(), frame)["fields"]["syringe0"] == 1
    with pytest.raises(Unsupported, match="cannot return Sample.syringe0"):
        imc.decode("imc", frame)


def test_oversized_message_is_a_size_limit(imc):
    message = {"abbrev": "SmsRx", "fields": {"source": "", "data": "00" * 65600}}
    with pytest.raises(Rejected) as caught:
        imc.encode("imc", message, "le")
    assert caught.value.rule == "size-limit"


def test_fp32_signalling_nan_arrives_quiet(imc):
    """Widening the f32 bits to a Python float quiets a signalling NaN before imcpy sees it."""
    message = sample("LblRange")
    message["fields"]["range"] = "nan:7f800001"
    assert imc.decode("imc", imc.encode("imc", message, "le"))["fields"]["range"] == "nan:7fc00001"
