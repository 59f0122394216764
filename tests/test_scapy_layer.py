"""The scapy layer for IMC (imc_conformance.scapy) against the reference codec and the corpus."""

from __future__ import annotations

import importlib
import pickle
import struct
import subprocess
import sys

import pytest
from scapy.compat import raw
from scapy.layers.inet import IP, UDP
from scapy.layers.l2 import Ether
from scapy.packet import Padding, Raw
from scapy.utils import rdpcap, wrpcap

from imc_conformance.kinds.vector.errors import FrameError
from imc_conformance.scapy import IMC, bind, from_decoded, message_class, to_decoded, unbind
from imc_conformance.scapy.binding import PORTS
from imc_conformance.scapy.byteorder import packing
from imc_conformance.scapy.messages import Message, NullMessage, field_of
from imc_conformance.suites import load_suite
from imc_conformance.suites.imc import codec
from imc_conformance.suites.imc.crc16 import crc16
from imc_conformance.suites.imc.definitions import SCALAR_FORMATS, FieldDef

MESSAGES = [m.abbrev for m in load_suite("imc").defs.suite_messages]
LBL_RANGE = {"abbrev": "LblRange", "header": {"timestamp": 1700000000.5, "src": 30, "src_ent": 1, "dst": 16641,
                                             "dst_ent": 255}, "fields": {"id": 3, "range": 812.5}}


def by_bits(value):
    """``value`` with every float replaced by its bits, so that -0.0 and 0.0 differ and NaNs compare."""
    if isinstance(value, float):
        return ("float", struct.pack("<d", value))
    if isinstance(value, dict):
        return {k: by_bits(v) for k, v in value.items()}
    if isinstance(value, list):
        return [by_bits(v) for v in value]
    return value


def expects(case, outcome: str) -> bool:
    expect = case.data["expect"]
    return outcome == expect if isinstance(expect, str) else outcome in expect.values()


def frames(cases, group=None):
    """(case, byte order, frame) of every vector case's frames, of one message group if given."""
    for case in cases:
        if case.kind == "vector" and "frames" in case.data and group in (None, case.group):
            for order, hexed in case.data["frames"].items():
                yield case, order, bytes.fromhex(hexed)


@pytest.fixture
def bindings():
    """Scapy's UDP bindings, restored after the test."""
    guess, overload = UDP.payload_guess[:], IMC._overload_fields.copy()
    yield
    UDP.payload_guess, IMC._overload_fields = guess, overload


def imc_bound() -> int:
    return sum(cls is IMC for _, cls in UDP.payload_guess)


# ---------------------------------------------------------------- the corpus


@pytest.mark.parametrize("group", MESSAGES)
def test_valid_frames_dissect_like_the_codec_and_build_back(group, cases, defs):
    checked = 0
    for case, order, frame in frames(cases, group):
        if not expects(case, "valid"):
            continue
        decoded = codec.decode(defs, frame)
        pkt = IMC(frame)
        assert by_bits(to_decoded(pkt)) == by_bits(decoded), (case.id, order)
        assert bytes(pkt) == frame, (case.id, order)
        assert bytes(from_decoded(decoded, order)) == frame, (case.id, order)
        checked += 1
    assert checked


def test_every_frame_the_codec_decodes_dissects_alike(cases, defs):
    """Acceptable frames too: trailing bytes become padding, unused payload bytes a Raw after the fields."""
    acceptable = 0
    for case, order, frame in frames(cases):
        try:
            decoded = codec.decode(defs, frame)
        except FrameError:
            continue
        assert by_bits(to_decoded(IMC(frame))) == by_bits(decoded), (case.id, order)
        acceptable += expects(case, "acceptable")
    assert acceptable


def test_every_corpus_frame_dissects_and_builds_back_unchanged(cases):
    """Broken frames included: cut, bad sync, size or CRC, unknown ids, fields overrunning the payload."""
    for case, order, frame in frames(cases):
        pkt = IMC(frame)
        if frame:  # IMC(b"") is IMC(), as for every scapy layer
            assert bytes(pkt) == frame, (case.id, order)


def test_changing_the_sync_reencodes_every_field(cases):
    """A dissected frame turned to the other byte order builds as the codec encodes it, nested messages
    included, once its CRC is deleted (a dissected CRC is a given value, kept as it is)."""
    case = next(c for c in cases if c.id == "imc/HistoricData/realistic/two-samples")
    le, be = (bytes.fromhex(case.data["frames"][o]) for o in ("le", "be"))
    for source, target, order in ((le, be, "be"), (be, le, "le")):
        pkt = IMC(source)
        pkt.sync = order
        assert bytes(pkt)[:-2] == target[:-2] and IMC(bytes(pkt)).crc16 == IMC(source).crc16
        del pkt.crc16
        assert bytes(pkt) == target


# ---------------------------------------------------------------- building


@pytest.mark.parametrize("order", ["le", "be"])
def test_building_computes_mgid_size_and_crc(order, defs):
    pkt = IMC(sync=order, src=30, src_ent=1, dst=16641, timestamp=1700000000.5,
              message=message_class("LblRange")(id=3, range=812.5))
    assert (pkt.mgid, pkt.size, pkt.crc16) == (None, None, None)
    frame = bytes(pkt)
    assert frame == codec.encode(defs, LBL_RANGE, order)
    again = IMC(frame)
    assert (again.byte_order, again.mgid, again.size, again.crc16) == (order, 200, 5, crc16(frame[:-2]))


@pytest.mark.parametrize("order", ["le", "be"])
def test_given_values_are_kept_so_broken_frames_can_be_crafted(order, defs):
    e = codec.ORDERS[order]
    bad_crc = bytes(IMC(sync=order, crc16=0, message=message_class("LblRange")(id=3, range=812.5)))
    assert bad_crc[-2:] == b"\0\0"
    with pytest.raises(FrameError) as error:
        codec.decode(defs, bad_crc)
    assert error.value.rule == "crc"

    pkt = from_decoded(LBL_RANGE, order)
    pkt.size = 9
    with pytest.raises(FrameError) as error:
        codec.decode(defs, bytes(pkt))
    assert error.value.rule == "size-exceeds-data"

    pkt = from_decoded(LBL_RANGE, order)
    pkt.mgid = 150
    frame = bytes(pkt)
    assert struct.unpack_from(e + "H", frame, 2)[0] == 150
    assert frame[2:4] != codec.encode(defs, LBL_RANGE, order)[2:4]


def test_a_frame_without_message_or_mgid_does_not_build():
    with pytest.raises(ValueError, match="mgid"):
        bytes(IMC())
    assert IMC(bytes(IMC(mgid=150))).message.definition.abbrev == "Heartbeat"


@pytest.mark.parametrize("value", [0.1, -0.0, "inf", "-inf", "nan", "nan:7fc00001", "nan:ffc00000", "nan:7f800001"])
@pytest.mark.parametrize("order", ["le", "be"])
def test_float_bits_are_kept(value, order, defs):
    """fp32 included, where a signalling NaN (7f800001) would lose its bits through a Python float."""
    message = {"abbrev": "LblRange", "fields": {"id": 1, "range": value}}
    frame = bytes(from_decoded(message, order))
    assert frame == codec.encode(defs, message, order)
    assert by_bits(to_decoded(IMC(frame))["fields"]["range"]) == by_bits(value)
    assert bytes(IMC(frame)) == frame


@pytest.mark.parametrize("order", ["le", "be"])
@pytest.mark.parametrize("type_", sorted(SCALAR_FORMATS))
def test_every_scalar_type_packs_like_struct(type_, order):
    """Every scalar type, including the widths no IMC message uses (int32_t, int64_t)."""
    fdef = FieldDef(abbrev="v", name="v", type=type_, clause="test")
    cls = type("_Scalar", (Message,), {"fields_desc": [field_of(fdef)]})  # "_": not listed in scapy's layers
    for value in (-1.5, 3.25) if fdef.is_float else fdef.int_bounds:
        expected = struct.pack(codec.ORDERS[order] + SCALAR_FORMATS[type_], value)
        with packing(order):  # what a frame in this byte order sets around its message
            assert raw(cls(v=value)) == expected
            assert cls(expected).v == value


# ---------------------------------------------------------------- classes and display


def test_message_classes_follow_the_definitions(defs):
    for mdef in defs.messages:
        cls = message_class(mdef.abbrev)
        assert cls is message_class(mdef.id)
        assert cls.__name__ == cls().name == mdef.abbrev and cls.definition is mdef
        assert [f.name for f in cls.fields_desc] == [f.abbrev for f in mdef.fields]
    with pytest.raises(KeyError):
        message_class("NoSuchMessage")
    message = message_class("LblRange")(id=3, range=812.5)
    assert pickle.loads(pickle.dumps(message)) == message


def test_show_names_fields_enums_and_flags(defs):
    op = next(v for v in defs["AcousticOperation"].field("op").enum_values if v.abbrev == "RANGE")
    pkt = from_decoded({"abbrev": "AcousticOperation", "fields": {
        "op": op.value, "system": "b1", "range": 10.5,
        "msg": {"abbrev": "LblRange", "fields": {"id": 1, "range": 2.5}}}}, "be")
    assert "mgid      = None" in pkt.show(dump=True)  # computed when built
    assert "mgid      = AcousticOperation" in pkt.show2(dump=True)
    for text in (pkt.show(dump=True), pkt.show2(dump=True)):
        assert "sync      = be" in text and "###[ AcousticOperation ]###" in text and "op        = RANGE" in text
        assert "system    = b'b1'" in text and "range     = 10.5 m" in text and "###[ LblRange ]###" in text
    assert "crc16     = 0x" in pkt.show2(dump=True)
    assert IMC(raw(pkt)).message.op == op.value
    assert repr(message_class("AcousticOperation")(op="RANGE")).startswith("<AcousticOperation  op=RANGE")

    flags = {v.abbrev: v.value for v in defs["AnnounceService"].field("service_type").enum_values}
    service = message_class("AnnounceService")(service="imc+udp://10.0.0.1:6001/", service_type="EXTERNAL+LOCAL")
    assert int(service.service_type) == flags["EXTERNAL"] | flags["LOCAL"]
    assert "service_type= EXTERNAL+LOCAL" in IMC(raw(IMC(message=service))).show(dump=True)


def test_null_messages_inline_and_in_lists(defs):
    message = {"abbrev": "LblConfig", "fields": {"op": 0, "beacons": [
        {"abbrev": "LblBeacon", "fields": {"beacon": "b1", "lat": 0.7, "lon": -0.15, "depth": 3.0,
                                           "query_channel": 1, "reply_channel": 2, "transponder_delay": 3}},
        None]}}
    for order in ("le", "be"):
        pkt = IMC(bytes(from_decoded(message, order)))
        assert isinstance(pkt.message.beacons[1], NullMessage)
        assert by_bits(to_decoded(pkt)["fields"]) == by_bits(message["fields"])
        assert "###[ null message ]###" in pkt.show(dump=True)
    operation = IMC(raw(from_decoded({"abbrev": "AcousticOperation", "fields": {"msg": None}})))
    assert operation.message.msg is None and to_decoded(operation)["fields"]["msg"] is None


# ---------------------------------------------------------------- robustness


def test_cut_frames_unknown_ids_and_broken_payloads_dissect():
    frame = bytes(from_decoded(LBL_RANGE))
    for end in range(1, len(frame)):
        pkt = IMC(frame[:end])
        assert bytes(pkt) == frame[:end]
    cut = IMC(frame[:23])
    assert cut.size == 5 and cut.crc16 is None and isinstance(cut.message, Raw) and cut.message.load == frame[20:23]
    assert IMC(frame[:1]).mgid is None

    unknown = IMC(bytes(IMC(mgid=999, message=Raw(b"\x01\x02"))))
    assert unknown.mgid == 999 and unknown.message.load == b"\x01\x02"
    with pytest.raises(ValueError, match="did not dissect"):
        to_decoded(unknown)

    short = IMC(bytes(IMC(mgid=200, message=Raw(b"\x01\x02"))))  # LblRange needs 5 bytes
    assert isinstance(short.message, Raw) and short.message.load == b"\x01\x02"

    unknown_inline = IMC(bytes(IMC(mgid=206, message=Raw(b"\xe7\x03"))))  # AcousticMessage holding id 999
    assert isinstance(unknown_inline.message, Raw)


def test_only_the_first_frame_counts():
    first, second = bytes(from_decoded(LBL_RANGE)), bytes(from_decoded(LBL_RANGE, "be"))
    pkt = IMC(first + second)
    assert pkt[Padding].load == second and bytes(pkt) == first + second
    assert to_decoded(pkt) == LBL_RANGE


# ---------------------------------------------------------------- binding


def test_importing_the_package_binds_nothing():
    code = ("import imc_conformance.scapy as s; from scapy.layers.inet import UDP; "
            "assert not [c for _, c in UDP.payload_guess if c is s.IMC]; "
            "assert UDP not in s.IMC._overload_fields")
    subprocess.run([sys.executable, "-c", code], check=True, timeout=120)


def udp(sport: int, dport: int, payload: bytes):
    return (Ether(src="02:00:00:00:00:01", dst="02:00:00:00:00:02") / IP(src="10.0.0.1", dst="10.0.0.2")
            / UDP(sport=sport, dport=dport) / Raw(payload))


def test_bind_dissects_the_imc_ports_and_unbind_undoes_it(bindings, tmp_path):
    frame = bytes(from_decoded(LBL_RANGE, "be"))
    assert imc_bound() == 0
    bind()
    bind()
    assert imc_bound() == 2 * len(PORTS)
    pkt = Ether(raw(udp(6002, 6001, frame)))
    assert IMC in pkt and to_decoded(pkt) == LBL_RANGE
    assert IMC in Ether(raw(udp(40000, 30100, frame))) and IMC in Ether(raw(udp(6030, 40000, frame)))
    assert IMC not in Ether(raw(udp(40000, 40001, frame)))
    assert (UDP() / IMC()).sport == (UDP() / IMC()).dport == 6001

    path = tmp_path / "imc.pcap"
    wrpcap(str(path), [udp(6001, 6001, frame + b"pad"), udp(6001, 30100, bytes(from_decoded(LBL_RANGE)))])
    read = rdpcap(str(path))
    assert [to_decoded(p) for p in read] == [LBL_RANGE, LBL_RANGE]
    assert read[0][Padding].load == b"pad"

    unbind()
    assert imc_bound() == 0 and UDP not in IMC._overload_fields
    assert IMC not in Ether(raw(udp(6002, 6001, frame)))
    assert IMC not in rdpcap(str(path))[0]


def test_importing_bound_binds(bindings):
    sys.modules.pop("imc_conformance.scapy.bound", None)
    importlib.import_module("imc_conformance.scapy.bound")
    assert imc_bound() == 2 * len(PORTS)
