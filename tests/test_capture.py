"""Captures: every link layer, capture format and IP feature the pcap command reads, every frame rule of the
corpus found in captured datagrams, every exchange rule caught in captured exchanges, and bad input."""

from __future__ import annotations

import json
import struct
from decimal import Decimal

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scapy.layers.inet import IP, UDP, fragment
from scapy.layers.inet6 import IPv6, IPv6ExtHdrFragment, fragment6
from scapy.layers.l2 import CookedLinux, CookedLinuxV2, Dot1AD, Dot1Q, Ether, Loopback
from scapy.packet import Raw
from scapy.utils import PcapNgWriter, wrpcap

from imc_conformance.capture.judge import CaptureJudge, Selection
from imc_conformance.capture.records import CaptureError, records
from imc_conformance.capture.writing import PCAP_HEADER, ethernet_udp, pcap_record
from imc_conformance.cli import main
from imc_conformance.core.cases import expectation
from imc_conformance.core.verdicts import Verdict
from imc_conformance.files import open_corpus
from imc_conformance.suites import load_suite
from imc_conformance.suites.imc import codec
from imc_conformance.suites.imc.traffic import write_capture

SUITE = load_suite("imc")
DEFS = SUITE.defs
EDITION = "imc-5.4.30"
STATION, VEHICLE = 0x4CF0, 30
T0 = 1_700_000_000.0


def frame(abbrev: str, fields: dict | None = None, src: int = STATION, dst: int = VEHICLE, order: str = "le") -> bytes:
    header = {"timestamp": 1.0, "src": src, "src_ent": 255, "dst": dst, "dst_ent": 255}
    return codec.encode(DEFS, {"abbrev": abbrev, "header": header, "fields": fields or {}}, order)


def named(message: str, field: str, name: str) -> int:
    return SUITE.wire.resolve(message, field, name, EDITION)


def judge(buf: bytes, **selection):
    j = CaptureJudge("imc", SUITE.capture_rules(), EDITION, Selection(**selection))
    for record in records(buf):
        j.feed(record)
    return j.result(implementation="test", started="2026-01-01T00:00:00+00:00", duration=0.0, strict=False,
                    title="IMC")


def cases(result) -> dict:
    return {c.id: c for c in result.cases}


def pcap(items, linktype: int = 1) -> bytes:
    """A microsecond pcap of (seconds after T0, link-layer bytes) records."""
    head = PCAP_HEADER[:20] + struct.pack("<I", linktype)
    return head + b"".join(pcap_record(T0 + t, data) for t, data in items)


def udp(payload: bytes, src=("10.0.0.1", 6001), dst=("10.0.0.30", 6002)) -> bytes:
    return ethernet_udp(src[0], src[1], dst[0], dst[1], payload)


# ---------------------------------------------------------------- link layers, formats, IP

HEARTBEAT = frame("Heartbeat", src=VEHICLE, dst=0xFFFF)
INNER = IP(src="10.0.0.1", dst="10.0.0.30") / UDP(sport=6001, dport=6002) / Raw(HEARTBEAT)
LINKS = {
    "ethernet": (Ether() / INNER, 1),
    "vlan": (Ether() / Dot1Q(vlan=7) / INNER, 1),
    "qinq": (Ether() / Dot1AD(vlan=3) / Dot1Q(vlan=7) / INNER, 1),
    "sll": (CookedLinux(proto=0x0800) / INNER, 113),
    "sll2": (CookedLinuxV2(proto=0x0800) / INNER, 276),
    "bsd-loopback": (Loopback(type=2) / INNER, 0),
    "raw-ip": (INNER, 101),
    "ipv6": (Ether() / IPv6(src="fd00::1", dst="fd00::30") / UDP(sport=6001, dport=6002) / Raw(HEARTBEAT), 1),
}


@pytest.mark.parametrize("link", LINKS)
def test_every_link_layer_is_read(link, tmp_path):
    packet, linktype = LINKS[link]
    packet.time = T0 + 0.25
    wrpcap(str(tmp_path / "c.pcap"), [packet], linktype=linktype)
    result = judge((tmp_path / "c.pcap").read_bytes())
    valid = cases(result)["imc/Heartbeat/capture/frame/valid"]
    assert valid.verdict is Verdict.PASS and valid.checks[0].detail.startswith("1 frame")
    assert "1 records, 1 datagrams" in result.notes[0]


def test_microsecond_nanosecond_big_endian_and_pcapng_captures_give_the_same_times(tmp_path):
    bad = bytearray(HEARTBEAT)
    bad[-1] ^= 1
    packets = [Ether() / IP(src="10.0.0.1", dst="10.0.0.30") / UDP(sport=6001, dport=6002) / Raw(data)
               for data in (HEARTBEAT, bytes(bad))]
    packets[0].time, packets[1].time = Decimal(int(T0)) + Decimal("0.5"), Decimal(int(T0)) + Decimal("1.000001")
    wrpcap(str(tmp_path / "us.pcap"), packets)
    wrpcap(str(tmp_path / "ns.pcap"), packets, nano=True)
    writer = PcapNgWriter(str(tmp_path / "c.pcapng"))
    for p in packets:
        writer.write(p)
    writer.close()
    little = (tmp_path / "us.pcap").read_bytes()
    big = b"\xa1\xb2\xc3\xd4" + b"".join(  # the same capture written by a big-endian machine
        struct.pack(">" + fmt, *struct.unpack("<" + fmt, little[a:b]))
        for fmt, a, b in (("HHiIII", 4, 24),)) + b"".join(
        struct.pack(">IIII", *struct.unpack_from("<IIII", little, pos)) + little[pos + 16:pos + 16 + n]
        for pos, n in _records(little))
    for name, buf in [("us", little), ("ns", (tmp_path / "ns.pcap").read_bytes()), ("be", big),
                      ("ng", (tmp_path / "c.pcapng").read_bytes())]:
        got = list(records(buf))
        assert [r.number for r in got] == [1, 2], name
        assert got[1].time - got[0].time == pytest.approx(0.500001, abs=1e-6), name
        crc = cases(judge(buf))["imc/Heartbeat/capture/frame/crc"]
        assert crc.checks[1].check == "frame 2" and "at 0.500001 s" in crc.checks[1].detail, name


def _records(buf: bytes):
    pos = 24
    while pos < len(buf):
        n = struct.unpack_from("<I", buf, pos + 8)[0]
        yield pos, n
        pos += 16 + n


def test_ip_fragments_are_reassembled_in_any_order(tmp_path):
    big = frame("AcousticSystems", {"list": "x" * 3000}, src=VEHICLE, dst=STATION)
    v4 = fragment(IP(src="10.0.0.30", dst="10.0.0.1", id=77) / UDP(sport=6002, dport=6001) / Raw(big), fragsize=1000)
    v6 = fragment6(IPv6(src="fd00::30", dst="fd00::1") / IPv6ExtHdrFragment(id=9) / UDP(sport=6002, dport=6001)
                   / Raw(big), 1200)
    packets = [Ether() / p for p in list(reversed(v4)) + v6[1:] + v6[:1]]
    for i, p in enumerate(packets):
        p.time = T0 + i / 100
    wrpcap(str(tmp_path / "f.pcap"), packets)
    result = judge((tmp_path / "f.pcap").read_bytes())
    valid = cases(result)["imc/AcousticSystems/capture/frame/valid"]
    assert valid.checks[0].detail.startswith("2 frames")
    assert not any("reassembled" in n for n in result.notes)


def test_a_fragment_never_completed_is_noted(tmp_path):
    big = frame("AcousticSystems", {"list": "x" * 3000}, src=VEHICLE, dst=STATION)
    parts = fragment(IP(src="10.0.0.30", dst="10.0.0.1", id=78) / UDP(sport=6002, dport=6001) / Raw(big), fragsize=1000)
    wrpcap(str(tmp_path / "f.pcap"), [Ether() / p for p in parts[:-1]])
    result = judge((tmp_path / "f.pcap").read_bytes())
    assert "1 IP datagrams never reassembled (fragments missing from the capture)" in result.notes
    assert result.exit_code() == 2  # nothing was judged


def test_a_datagram_cut_by_the_snaplen_is_inconclusive_not_invalid():
    whole = udp(frame("LblRange", {"id": 1, "range": 5.0}, src=VEHICLE, dst=STATION))
    cut = struct.pack("<IIII", int(T0), 0, 50, len(whole)) + whole[:50]
    result = judge(PCAP_HEADER + cut)
    case = cases(result)["imc/LblRange/capture/frame/truncated-by-capture"]
    assert case.verdict is Verdict.INCONCLUSIVE and "snaplen cut the datagram" in case.checks[1].detail
    assert result.exit_code() == 2  # nothing could be judged


def test_other_traffic_is_counted_apart():
    from imc_conformance.suites.imc.imc_xml import fetch_imc_xml

    fetch_imc_xml()  # the whole IMC.xml in the cache, which names the messages outside the suite
    outside = bytearray(frame("Heartbeat", src=VEHICLE, dst=STATION))
    struct.pack_into("<H", outside, 2, 350)  # EstimatedState: a message outside the suite
    outside[-2:] = struct.pack("<H", __import__("imc_conformance.suites.imc.crc16", fromlist=["crc16"]).crc16(
        bytes(outside[:-2])))
    buf = pcap([(0, udp(HEARTBEAT)), (1, udp(b"not imc")), (2, udp(bytes(outside))),
                (3, udp(HEARTBEAT, dst=("10.0.0.30", 9999), src=("10.0.0.1", 9998))),
                (4, Ether(type=0x0806).build() + bytes(28))])
    result = judge(buf)
    assert result.notes[1].startswith("1 frame of 1 message the suite does not cover (framing checked only): EstimatedState (1)")
    assert "1 not judged: datagrams on the ports that are not frames of the suite" in result.notes
    assert "1 not judged: UDP on other ports" in result.notes
    assert "1 not judged: not IP" in result.notes


# ---------------------------------------------------------------- frames: the corpus's rules

def corpus_frames():
    _, everything = open_corpus("imc")
    for case in everything:
        if case.kind == "vector" and expectation(case.data, EDITION) and "frames" in case.data:
            for order, hexed in case.data["frames"].items():
                yield case, order, bytes.fromhex(hexed)


def test_every_corpus_frame_gets_the_corpus_verdict_rule_and_offset():
    """Valid and acceptable frames are valid; an invalid one breaks its vector's rule at the codec's offset.
    Two differences are the capture's by design: a datagram without IMC's synchronization number (wrong, or
    fewer than 2 bytes) is not counted as IMC, a frame of an id the definitions lack is a message outside the suite (DUNE sends hundreds),
    and an inline id no IMC.xml names makes the frame not judged (INCONCLUSIVE: the rest of it cannot be read)."""
    items, expected = [], {}
    for case, order, data in corpus_frames():
        if len(data) > 65000:
            continue  # one UDP datagram carries 65,507 bytes
        items.append((len(items) / 1000, udp(data)))
        expected[len(items)] = case, data
    result = judge(pcap(items), listed=100000)
    seen = {}
    for c in result.cases:
        for check in c.checks:
            if check.check.startswith("frame ") and "/frame/" in c.id:
                seen[int(check.check.split()[1])] = (c, check)
    judged_valid = sum(int(c.checks[0].detail.split()[0].replace(",", "")) for c in result.cases
                       if c.id.endswith("/frame/valid"))
    not_imc = outside = unreadable = 0
    for n, (case, data) in expected.items():
        rule = case.data.get("rule") if expectation(case.data, EDITION) == "invalid" else None
        if rule is None:
            assert n not in seen, case.id
        elif rule == "sync" or len(data) < 2:  # no synchronization number
            not_imc += 1
        elif rule == "unknown-id" and n not in seen:
            outside += 1
        else:
            c, check = seen[n]
            if rule == "unknown-inline-id":  # traffic: an inline id no IMC.xml names leaves the frame unreadable
                assert c.rule == "inline-outside-definitions" and c.verdict == Verdict.INCONCLUSIVE, (case.id, c.id)
                unreadable += 1
                continue
            assert c.rule == rule, (case.id, c.id)
            try:
                codec.decode(DEFS, bytes.fromhex(check.actual))
            except Exception as exc:  # the codec's offset and wording
                assert f"byte {exc.offset}: {exc.detail}" in check.detail, case.id
    assert judged_valid == sum(1 for n in expected if n not in seen) - not_imc - outside
    assert f"{not_imc} not judged: datagrams on the ports that are not frames of the suite" in result.notes
    assert not_imc > 50 and outside > 50 and unreadable > 0 and judged_valid > 1500


# ---------------------------------------------------------------- exchanges

def exchange(*frames_at, end: float | None = None):
    """Judge (seconds, sender, frame) items; a last Heartbeat at ``end`` sets where the capture ends."""
    items = [(t, udp(data, *((("10.0.0.30", 6002), ("10.0.0.1", 6001)) if sender == VEHICLE else ())))
             for t, sender, data in frames_at]
    if end is not None:
        items.append((end, udp(HEARTBEAT)))
    return cases(judge(pcap(items)))


def request(req_id=7, src=STATION, dst=VEHICLE):
    return frame("AcousticRequest", {"req_id": req_id, "destination": "p", "timeout": 10.0, "range": 0.0,
                                     "type": named("AcousticRequest", "type", "MSG"), "msg": None}, src, dst)


def status(name: str, req_id=7, dst=STATION, src=VEHICLE, type_="MSG"):
    return frame("AcousticStatus", {"req_id": req_id, "type": named("AcousticStatus", "type", type_),
                                    "status": named("AcousticStatus", "status", name), "info": "", "range": 0.0},
                 src, dst)


EX = "imc/AcousticRequest/capture/exchange/acoustic-request"


def test_a_well_behaved_exchange_passes():
    got = exchange((0, STATION, request()), (0.5, VEHICLE, status("QUEUED")), (2, VEHICLE, status("SENT")), end=30)
    assert {k: c.verdict for k, c in got.items() if "exchange" in k} == {
        f"{EX}/answered": Verdict.PASS, f"{EX}/to-requester": Verdict.PASS, f"{EX}/terminal": Verdict.PASS}


def test_an_unanswered_request_fails_with_its_frame_and_time():
    got = exchange((0, STATION, request()), end=30)
    case = got[f"{EX}/answered"]
    assert case.verdict is Verdict.FAIL and case.checks[1].check == "frame 1"
    assert "no AcousticStatus from system 30 to 19696 within 20 s" in case.checks[1].detail and "at 0.000000 s" in case.checks[1].detail


def test_a_request_to_system_0_is_for_no_system_in_particular():
    """System 0 names no system (DUNE addresses its Announce to it): any node's reply answers a request to it, and none
    at all is the open reading addressed-elsewhere, never a FAIL."""
    answered = exchange((0, STATION, request(dst=0)), (0.5, VEHICLE, status("SENT")), end=30)
    assert answered[f"{EX}/answered"].verdict is Verdict.PASS
    silent = exchange((0, STATION, request(dst=0)), end=30)
    assert silent[f"{EX}/reading/addressed-elsewhere"].verdict is Verdict.IMPL_DEFINED and f"{EX}/answered" not in silent


def test_a_capture_ending_before_the_bound_is_inconclusive():
    assert exchange((0, STATION, request()), end=3)[f"{EX}/answered"].verdict is Verdict.INCONCLUSIVE


def test_a_req_id_not_echoed_fails_at_the_reply():
    got = exchange((0, STATION, request(7)), (1, VEHICLE, status("SENT", req_id=8)), end=30)
    case = got[f"{EX}/echo-req_id"]
    assert case.verdict is Verdict.FAIL and case.checks[1].check == "frame 2"
    assert "no AcousticStatus echoed req_id=7 within 20 s; this one carries req_id=8" in case.checks[1].detail


def test_a_reply_whose_request_is_not_in_the_capture_is_not_judged():
    got = exchange((1, VEHICLE, status("SENT", req_id=8)), end=30)
    assert not [k for k in got if "exchange" in k]


def test_a_status_after_the_terminal_one_is_caught_at_the_level_of_its_rule():
    """AcousticStatus gives its states no meaning in the seed: one terminal state and nothing after it is DUNE's
    practice (ambiguity acoustic-status-meaning), a SHOULD."""
    got = exchange((0, STATION, request()), (1, VEHICLE, status("SENT")), (2, VEHICLE, status("QUEUED")), end=30)
    case = got[f"{EX}/after-terminal"]
    assert case.verdict is Verdict.NON_STRICT and "status=QUEUED after the terminal state (frame 2)" in case.checks[1].detail


def test_a_request_ending_in_busy_is_a_reading_not_a_failure():
    got = exchange((0, STATION, request()), (1, VEHICLE, status("BUSY")), end=30)
    assert got[f"{EX}/terminal"].verdict is Verdict.PASS and f"{EX}/after-terminal" not in got
    reading = got[f"{EX}/reading/busy-ends-request"]
    assert reading.verdict is Verdict.IMPL_DEFINED and "read as the end of the request" in reading.checks[1].detail


def test_busy_then_the_request_going_on_is_a_reading_not_a_failure():
    got = exchange((0, STATION, request()), (1, VEHICLE, status("BUSY")), (2, VEHICLE, status("IN_PROGRESS")),
                   (3, VEHICLE, status("SENT")), end=30)
    assert f"{EX}/after-terminal" not in got
    reading = got[f"{EX}/reading/busy-ends-request"]
    assert reading.verdict is Verdict.IMPL_DEFINED and "read as a delay" in reading.checks[1].detail


def test_a_reply_to_another_system_fails():
    got = exchange((0, STATION, request()), (1, VEHICLE, status("SENT", dst=0xFFFF)), end=30)
    case = got[f"{EX}/to-requester"]
    assert case.verdict is Verdict.FAIL and "sent to system 65535, not to the requester 19696" in case.checks[1].detail


def test_a_late_reply_fails_and_a_sequence_without_end_is_caught():
    got = exchange((0, STATION, request()), (25, VEHICLE, status("QUEUED")), end=80)
    assert "no AcousticStatus from system 30 to 19696 within 20 s" in got[f"{EX}/answered"].checks[1].detail
    got = exchange((0, STATION, request()), (1, VEHICLE, status("QUEUED")), end=80)
    assert got[f"{EX}/terminal"].verdict is Verdict.NON_STRICT  # DUNE's practice: acoustic-status-meaning
    assert "no terminal AcousticStatus within 20 s" in got[f"{EX}/terminal"].checks[1].detail


def test_a_resent_request_is_one_exchange_and_a_should_is_non_strict():
    got = exchange((0, STATION, request()), (1, STATION, request()), (2, VEHICLE, status("SENT")), end=30)
    assert got[f"{EX}/answered"].checks[0].detail.startswith("1 exchange ")
    tx = frame("IridiumMsgTx", {"req_id": 3, "ttl": 60, "destination": "", "data": ""})
    reply = frame("IridiumTxStatus", {"req_id": 3, "status": named("IridiumTxStatus", "status", "OK"), "text": ""},
                  VEHICLE, 0x1234)
    got = exchange((0, STATION, tx), (1, VEHICLE, reply), end=90)
    case = got["imc/IridiumMsgTx/capture/exchange/iridium-transmission/to-requester"]
    assert case.verdict is Verdict.NON_STRICT  # to-requester is a SHOULD for Iridium (imc-wire.md)


# ---------------------------------------------------------------- the command

def run(*argv, capsys=None):
    code = main(["pcap", *map(str, argv)])
    out = capsys.readouterr() if capsys else None
    return code, out


def test_generated_traffic_passes_clean_and_damage_is_found(tmp_path, capsys):
    info = write_capture(tmp_path / "clean.pcap", DEFS, SUITE.wire, EDITION, 3000, damaged=0.0)
    code, out = run(tmp_path / "clean.pcap", "--json", tmp_path / "r.json", capsys=capsys)
    doc = json.loads((tmp_path / "r.json").read_text())
    verdicts = {c["id"]: c["verdict"] for m in doc["messages"] for c in m["cases"]}
    assert info == {"frames": 3000, "damaged": 0}
    assert {v for k, v in verdicts.items() if not k.endswith("/answered")} == {"PASS"}
    assert code == 0, out.out
    info = write_capture(tmp_path / "noisy.pcap", DEFS, SUITE.wire, EDITION, 3000, damaged=0.05)
    code, out = run(tmp_path / "noisy.pcap", "--message", "LblRange", "--list-frames", "2", "--json", tmp_path / "n.json",
                    capsys=capsys)
    doc = json.loads((tmp_path / "n.json").read_text())
    assert code == 1 and [m["name"] for m in doc["messages"]] == ["LblRange"]
    failing = [c for c in doc["messages"][0]["cases"] if c["verdict"] == "FAIL"]
    assert failing and all(len([k for k in c["checks"] if k["check"].startswith("frame ")]) <= 2 for c in failing)
    assert any(k["check"] == "more" for c in failing for k in c["checks"])


def test_filters_by_address_and_time(tmp_path, capsys):
    write_capture(tmp_path / "c.pcap", DEFS, SUITE.wire, EDITION, 1000, damaged=0.0)
    for argv in (["--src", "10.0.0.30"], ["--host", "0x4cf0"], ["--start", "10", "--end", "19.99"]):
        code, _ = run(tmp_path / "c.pcap", *argv, "--json", tmp_path / "r.json", capsys=capsys)
        doc = json.loads((tmp_path / "r.json").read_text())
        notes = " ".join(doc["notes"])
        assert "not judged: outside the selection" in notes, argv
    doc = json.loads((tmp_path / "r.json").read_text())
    heartbeats = next(m for m in doc["messages"] if m["name"] == "Heartbeat")["cases"][0]["checks"][0]["detail"]
    assert heartbeats.startswith("10 frames")  # one a second, seconds 10 to 19


@pytest.mark.parametrize("content, message", [
    (b"", "empty, not a capture"),
    (b"hello world, not a capture", "not a pcap or pcapng capture (it starts 68656c6c)"),
    (PCAP_HEADER[:10], "a truncated pcap header (10 of 24 bytes)"),
    (PCAP_HEADER + b"\x00" * 20, "record 1 claims 0 bytes"),
])
def test_a_file_that_is_not_a_capture_is_one_line(tmp_path, capsys, content, message):
    path = tmp_path / "x.pcap"
    path.write_bytes(content)
    code, out = run(path, capsys=capsys)
    if message.startswith("record 1 claims"):
        assert code == 2  # a record of 0 bytes is read: nothing in it to judge
        return
    assert code == 2 and out.err.count("\n") == 1 and message in out.err and "Traceback" not in out.err


def test_a_truncated_capture_judges_the_frames_before_the_damage(tmp_path, capsys):
    buf = pcap([(0, udp(HEARTBEAT)), (1, udp(HEARTBEAT)), (2, udp(HEARTBEAT))])
    (tmp_path / "t.pcap").write_bytes(buf[:-10])
    code, out = run(tmp_path / "t.pcap", "--json", tmp_path / "r.json", capsys=capsys)
    doc = json.loads((tmp_path / "r.json").read_text())
    assert code == 2 and "record 3 is truncated" in out.err and "Traceback" not in out.err
    assert doc["messages"][0]["cases"][0]["checks"][0]["detail"].startswith("2 frames")
    assert any("record 3 is truncated" in n for n in doc["notes"])


def test_a_link_type_not_read_is_one_line(tmp_path, capsys):
    (tmp_path / "c.pcap").write_bytes(pcap([(0, b"\x00" * 40)], linktype=147))
    code, out = run(tmp_path / "c.pcap", capsys=capsys)
    assert code == 2 and "link type 147: not Ethernet, raw IP, Linux cooked capture or BSD loopback" in out.err
    assert out.err.count("\n") == 1


@pytest.mark.parametrize("argv, message", [
    (["missing.pcap"], "cannot read missing.pcap"),
    ([".", ], "cannot read ."),
    (["c.pcap", "--message", "Nope"], "unknown message(s): Nope"),
    (["c.pcap", "--suite", "ros_acomms"], "is not carried in datagrams"),
    (["c.pcap", "--start", "5", "--end", "1"], "--end 1 is before --start 5"),
])
def test_mistaken_options_are_one_line(tmp_path, capsys, monkeypatch, argv, message):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "c.pcap").write_bytes(pcap([(0, udp(HEARTBEAT))]))
    code, out = run(*argv, capsys=capsys)
    assert code == 2 and message in out.err and out.err.count("\n") == 1


def test_damaged_pcapng_blocks_are_errors_not_tracebacks():
    with pytest.raises(CaptureError, match="truncated or damaged"):
        list(records(b"\x0a\x0d\x0d\x0a" + struct.pack("<I", 9999) + b"\x4d\x3c\x2b\x1a" + bytes(20)))


# ---------------------------------------------------------------- the capture as a corpus (--adapter)

@pytest.mark.parametrize("adapter, verdicts_", [
    ("imcpy", {"PASS"}),
    ("Reference", {"PASS"}),
    ("CrcUnchecked", {"PASS", "FAIL"}),  # a mutant that accepts the frames whose CRC is wrong
])
def test_captured_frames_replayed_through_an_implementation(adapter, verdicts_, tmp_path, capsys):
    if adapter != "imcpy":  # a mutant of suites/imc/mutants.py, made over the definitions
        (tmp_path / "mutant.py").write_text(
            f"import sys\nsys.path.insert(0, {str(__import__('pathlib').Path(__file__).parent)!r})\n"
            f"from imc_conformance.suites.imc.mutants import {adapter}\nfrom imc_conformance.suites import load_suite\n"
            f"adapter = {adapter}(load_suite('imc').defs)\n")  # a mutant class named in mutants.py
        adapter = f"{tmp_path / 'mutant.py'}:adapter"
    write_capture(tmp_path / "c.pcap", DEFS, SUITE.wire, EDITION, 600, damaged=0.1)
    code, out = run(tmp_path / "c.pcap", "--adapter", adapter, "--list-frames", "3", "--json", tmp_path / "r.json",
                    capsys=capsys)
    doc = json.loads((tmp_path / "r.json").read_text())
    decoded = {c["id"]: c for m in doc["messages"] for c in m["cases"] if "/capture/decode/" in c["id"]}
    assert {c["verdict"] for c in decoded.values()} == verdicts_
    assert any("distinct frames decoded by the adapter" in n for n in doc["notes"])
    if "FAIL" in verdicts_:
        failing = [c for c in decoded.values() if c["verdict"] == "FAIL"]
        assert {c["id"].rsplit("/", 1)[1] for c in failing} == {"crc"}
        assert all(len([k for k in c["checks"] if k["check"].startswith("frame ")]) <= 3 for c in failing)


# ---------------------------------------------------------------- hostile captures

def _small_captures(tmp_path_factory):
    folder = tmp_path_factory.mktemp("captures")
    packets = [Ether() / IP(src="10.0.0.1", dst="10.0.0.30") / UDP(sport=6001, dport=6002) / Raw(request(n))
               for n in range(3)]
    packets += fragment(IP(src="10.0.0.30", dst="10.0.0.1", id=5) / UDP(sport=6002, dport=6001)
                        / Raw(frame("AcousticSystems", {"list": "y" * 900}, VEHICLE, STATION)), fragsize=400)
    packets = [p if Ether in p else Ether() / p for p in packets]
    wrpcap(str(folder / "c.pcap"), packets)
    writer = PcapNgWriter(str(folder / "c.pcapng"))
    for p in packets:
        writer.write(p)
    writer.close()
    return [(folder / "c.pcap").read_bytes(), (folder / "c.pcapng").read_bytes()]


@pytest.fixture(scope="module")
def small_captures(tmp_path_factory):
    return _small_captures(tmp_path_factory)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(which=st.integers(0, 1), edits=st.lists(st.tuples(st.integers(0, 10_000), st.integers(0, 255)), max_size=8),
       cut=st.integers(0, 10_000))
def test_a_damaged_capture_is_judged_or_refused_never_a_crash(small_captures, which, edits, cut):
    buf = bytearray(small_captures[which])
    for at, value in edits:
        buf[at % len(buf)] = value
    buf = bytes(buf[:len(buf) - cut % 64])
    j = CaptureJudge("imc", SUITE.capture_rules(), EDITION, Selection())
    try:
        for record in records(buf):  # as the pcap command does: the records before any damage are judged
            j.feed(record)
    except CaptureError:
        pass
    j.result(implementation="fuzz", started="2026-01-01T00:00:00+00:00", duration=0.0, strict=False, title="IMC")


def test_a_timestamp_no_calendar_holds_is_shown_in_seconds():
    result = judge(PCAP_HEADER + struct.pack("<IIII", 0xFFFFFFFF, 0, 0, 0) + struct.pack("<IIII", 0, 0, 0, 0))
    assert "from 4294967295.000000 s after 1970" in result.notes[0] or "from 2106-" in result.notes[0]
    ng = (b"\x0a\x0d\x0d\x0a" + struct.pack("<I", 28) + b"\x4d\x3c\x2b\x1a" + struct.pack("<HHq", 1, 0, -1)
          + struct.pack("<I", 28) + struct.pack("<IIHHI", 1, 20, 1, 0, 0) + struct.pack("<I", 20)
          + struct.pack("<II", 6, 32) + struct.pack("<IIIII", 0, 0xFFFFFFFF, 0xFFFFFFFF, 0, 0) + struct.pack("<I", 32))
    assert "s after 1970" in judge(ng).notes[0]  # 2^64 microseconds: no calendar date


def test_two_requesters_with_the_same_req_id_are_told_apart():
    other = 0x5000
    got = exchange((0, STATION, request(7)), (0.1, other, request(7, src=other)),
                   (1, VEHICLE, status("SENT", dst=other)), (2, VEHICLE, status("SENT")), end=30)
    assert got[f"{EX}/to-requester"].verdict is Verdict.PASS
    assert got[f"{EX}/answered"].checks[0].detail.startswith("2 exchanges")


def test_a_pcap_whose_link_type_carries_fcs_bits_is_read():
    head = PCAP_HEADER[:20] + struct.pack("<I", 1 | 0x1 << 28 | 0x1 << 26)  # Ethernet, the F bit and an FCS length
    result = judge(head + pcap_record(T0, udp(HEARTBEAT)))
    assert cases(result)["imc/Heartbeat/capture/frame/valid"].verdict is Verdict.PASS


def test_a_capture_result_is_schema_valid_and_re_renders_byte_for_byte(tmp_path, capsys):
    from imc_conformance.files import read_result
    from imc_conformance.render import RENDERERS

    write_capture(tmp_path / "c.pcap", DEFS, SUITE.wire, EDITION, 2000, damaged=0.1)
    run(tmp_path / "c.pcap", "--adapter", "imcpy", "--list-frames", "2", "--json", tmp_path / "r.json", capsys=capsys)
    again = read_result(tmp_path / "r.json")  # checked against the result schema
    assert RENDERERS["json"](again) == (tmp_path / "r.json").read_text(encoding="utf-8")
    checks = {k.check.split()[0] for c in again.cases for k in c.checks}
    assert checks == {"count", "frame", "more"}


# ---------------------------------------------------------------- found in review

def test_filters_never_hide_a_reply_from_the_exchange_rules():
    query = frame("AcousticSystemsQuery", {}, STATION, VEHICLE)
    answer = frame("AcousticSystems", {"list": "p"}, VEHICLE, STATION)
    buf = pcap([(0, udp(query)), (1, udp(answer, ("10.0.0.30", 6002), ("10.0.0.1", 6001))), (20, udp(HEARTBEAT))])
    answered = "imc/AcousticSystemsQuery/capture/exchange/acoustic-systems/answered"
    assert cases(judge(buf))[answered].verdict is Verdict.PASS
    assert cases(judge(buf, src="10.0.0.1"))[answered].verdict is Verdict.PASS  # the reply is still followed
    assert cases(judge(buf, dst=VEHICLE))[answered].verdict is Verdict.PASS
    assert cases(judge(buf, end=0.5))[answered].verdict is Verdict.INCONCLUSIVE  # the window ends first
    narrowed = judge(buf, src="10.0.0.1")
    assert narrowed.notes[0].startswith("3 records, 2 datagrams on the ports judged")  # the reply is not counted


def test_a_requesters_own_resend_to_anyone_is_no_answer():
    clear = frame("HistoricDataQuery", {"req_id": 5, "type": named("HistoricDataQuery", "type", "CLEAR"),
                                        "max_size": 0, "data": None}, STATION, 0xFFFF)
    got = exchange((0, STATION, clear), (1, STATION, clear + b""), end=30)
    case = got["imc/HistoricDataQuery/capture/exchange/historic-data-clear/answered"]
    assert case.verdict is not Verdict.PASS


def test_an_interface_description_without_a_body_is_damage_not_a_crash():
    damaged = (b"\x0a\x0d\x0d\x0a" + struct.pack("<I", 28) + b"\x4d\x3c\x2b\x1a" + struct.pack("<HHq", 1, 0, -1)
               + struct.pack("<I", 28) + struct.pack("<II", 1, 12) + struct.pack("<I", 12))
    with pytest.raises(CaptureError, match="an interface description before record 1 is damaged"):
        list(records(damaged))


def test_frame_numbers_count_the_blocks_wireshark_numbers(tmp_path):
    writer = PcapNgWriter(str(tmp_path / "c.pcapng"))
    writer.write(Ether() / INNER)
    writer.close()
    data = (tmp_path / "c.pcapng").read_bytes()
    custom = struct.pack("<II", 0x40000BAD, 16) + struct.pack("<I", 32473) + struct.pack("<I", 16)
    got = [r.number for r in records(data + custom + data[data.index(struct.pack("<I", 6)):])]
    assert got == [1, 3]  # the custom block is frame 2 in Wireshark


def test_written_records_keep_their_second_and_zones_are_not_on_the_wire():
    from imc_conformance.capture.writing import ip_udp

    record = pcap_record(1_700_000_000.9999996, b"x")
    assert struct.unpack_from("<II", record) == (1_700_000_001, 0)
    assert ip_udp("fe80::1%eth0", 5000, "fe80::2%eth0", 6002, b"x")[8:24] == __import__("socket").inet_pton(
        __import__("socket").AF_INET6, "fe80::1")


def test_a_frame_nested_beyond_the_codec_is_inconclusive_not_a_crash():
    inner = None
    for _ in range(400):  # RemoteCommands in RemoteCommands: valid IMC, deeper than Python recursion goes
        inner = {"abbrev": "RemoteCommand", "fields": {"original_source": 1, "destination": 2, "timeout": 0.0,
                                                       "cmd": inner}}
    data = bytearray(frame("RemoteCommand", {"original_source": 1, "destination": 2, "timeout": 0.0, "cmd": None},
                           VEHICLE, STATION))
    nested = b""
    for _ in range(400):
        nested = struct.pack("<HHHd", 188, 1, 2, 0.0) + nested
    payload = data[20:-2 - 2] + nested + struct.pack("<H", 0xFFFF)
    body = bytes(data[:4]) + struct.pack("<H", len(payload)) + bytes(data[6:20]) + payload
    from imc_conformance.suites.imc.crc16 import crc16
    whole = body + struct.pack("<H", crc16(body))
    case = cases(judge(pcap([(0, udp(whole))])))["imc/RemoteCommand/capture/frame/nested-too-deep"]
    assert case.verdict is Verdict.INCONCLUSIVE


def test_a_capture_read_from_standard_input(tmp_path):
    import subprocess
    import sys
    from pathlib import Path

    command = [str(Path(sys.executable).parent / "imc-conformance"), "pcap", "-", "--json", str(tmp_path / "r.json")]
    done = subprocess.run(command, input=pcap([(0, udp(HEARTBEAT))]), capture_output=True, timeout=120)
    assert done.returncode == 0, done.stderr
    doc = json.loads((tmp_path / "r.json").read_text())
    assert doc["messages"][0]["cases"][0]["id"] == "imc/Heartbeat/capture/frame/valid"


def test_a_watch_judges_exchanges_until_it_stops():
    j = CaptureJudge("imc", SUITE.capture_rules(), EDITION, Selection())
    for record in records(pcap([(0, udp(frame("AcousticSystemsQuery", {}, STATION, VEHICLE)))])):
        j.feed(record)
    result = j.result(implementation="w", started="x", duration=0.0, strict=False, title="IMC", until=T0 + 30)
    answered = cases(result)["imc/AcousticSystemsQuery/capture/exchange/acoustic-systems/answered"]
    assert answered.verdict is Verdict.FAIL  # 30 s of watching saw no answer within 5 s


def test_many_small_fragments_are_put_together_once():
    big = frame("AcousticSystems", {"list": "z" * 4000}, VEHICLE, STATION)
    parts = fragment(IP(src="10.0.0.30", dst="10.0.0.1", id=9) / UDP(sport=6002, dport=6001) / Raw(big), fragsize=8)
    result = judge(pcap([(0, (Ether() / p).build()) for p in reversed(parts)]))
    assert cases(result)["imc/AcousticSystems/capture/frame/valid"].checks[0].detail.startswith("1 frame")
    assert f"{len(parts) - 1:,} not judged: IP fragments (judged once their datagram is whole)" in result.notes


def test_a_request_echoed_back_from_its_addressee_is_no_new_request():
    got = exchange((0, STATION, request(7)), (0.5, VEHICLE, status("SENT")), (1, VEHICLE, request(7)), end=40)
    assert got[f"{EX}/answered"].verdict is Verdict.PASS  # DUNE's router sends a request back to its sender
    assert got[f"{EX}/answered"].checks[0].detail.startswith("1 exchange ")


@settings(max_examples=400, deadline=None)
@given(st.binary(min_size=0, max_size=30), st.data())
def test_the_one_call_ethernet_path_reads_a_datagram_as_the_general_path_does(payload, data):
    from imc_conformance.capture.datagrams import Dissector
    from imc_conformance.capture.records import Record

    frame = bytearray(ethernet_udp("10.0.0.1", 6001, "10.0.0.30", 6002, payload, 7))
    for _ in range(data.draw(st.integers(0, 3))):  # header bytes changed: version, lengths, flags, protocol...
        frame[data.draw(st.integers(12, min(len(frame), 42) - 1))] = data.draw(st.integers(0, 255))
    frame = bytes(frame[:data.draw(st.integers(0, len(frame)))])
    record = Record(3, 1.5, 1, frame, len(frame))
    fast, general = Dissector().datagram(record), Dissector().dissected(record)
    assert fast == general
