"""A real vehicle's other traffic (messages outside the suite, ids no IMC.xml has) beside the messages under test:
live runs, recorded runs judged by ``pcap``, and logs check its framing and judge it no further, a note counting it,
never a failure; a frame whose framing is broken, or of the null id, still fails. Everything on virtual time."""

from __future__ import annotations

import json
import struct

import pytest

from imc_conformance.cli import main
from imc_conformance.core.verdicts import Verdict
from imc_conformance.suites.imc import codec
from imc_conformance.suites.imc.crc16 import crc16
from imc_conformance.suites.imc.node import ReferenceNode

from live_harness import NODE, recorded_run, run_virtual

TRAFFIC = "vehicle-traffic"
NAMED = {350: "EstimatedState", 1: "EntityState", 7: "CpuUsage", 254: "EulerAngles", 263: "Temperature"}  # IMC.xml's


def sound(defs, mgid: int, payload: bytes, e: str = "<") -> bytes:
    body = struct.pack(e + "HHHdHBHB", defs.sync, mgid, len(payload), 1.7e9, 30, 0, 0xFFFF, 0xFF) + payload
    return body + struct.pack(e + "H", crc16(body))


def fetched_whole_xml() -> None:
    """The whole IMC.xml in the cache (fetched from imcpy's sdist on PyPI once, as ``--suite imc-full`` does), or the
    test skipped saying why: the cases that read inline messages outside the suite with it must not depend on whether
    another test fetched it first."""
    from imc_conformance.suites.imc.imc_xml import fetch_imc_xml

    try:
        fetch_imc_xml()
    except (RuntimeError, OSError) as exc:
        pytest.skip(f"the whole IMC.xml cannot be fetched: {exc}")


def outcome(result) -> dict[str, str]:
    return {c.id: c.detail for c in result.cases if c.verdict not in (Verdict.PASS, Verdict.IMPL_DEFINED)}


@pytest.mark.parametrize("edition", ["imc-5.4.30", "imc-5.4.11"])
def test_a_vehicles_other_traffic_fails_no_scenario_and_is_counted(suite, cases, edition):
    fetched_whole_xml()
    result, _ = run_virtual(suite, cases, edition, kinds=("scenario", "robustness"), variant=TRAFFIC, strict=True)
    reference, _ = run_virtual(suite, cases, edition, kinds=("scenario", "robustness"), strict=True)
    assert outcome(result) == {} and result.exit_code() == 0
    verdicts = {c.id: c.verdict for c in result.cases}
    assert {k: v for k, v in verdicts.items() if k in {c.id for c in reference.cases}} == {c.id: c.verdict for c in reference.cases}
    extra = {k: v for k, v in verdicts.items() if k not in {c.id for c in reference.cases}}
    assert extra and all(k.startswith("imc/HistoricData/passive/") and v == Verdict.PASS for k, v in extra.items())
    known = next(n for n in result.notes if "messages the suite does not cover (framing checked only)" in n)
    assert all(f"{name} (" in known for name in NAMED.values()) and "id 999" not in known
    undefined = next(n for n in result.notes if "no definition the suite has names" in n)
    assert "id 999 (" in undefined and "never a failure" in undefined


def test_a_recorded_run_with_that_traffic_is_judged_alike_by_pcap(suite, cases, tmp_path, whole_xml):
    path, out = tmp_path / "run.pcapng", tmp_path / "judged.json"
    live = recorded_run(suite, cases, path, variant=TRAFFIC)
    assert main(["pcap", str(path), "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    judged = {c["id"]: c["verdict"] for m in doc["messages"] for c in m["cases"]}
    unjudged = {k: v for k, v in judged.items() if v not in ("PASS", "IMPL_DEFINED")}
    alike = {c.id: c.verdict.value for c in live.cases}
    if whole_xml == "cached":
        assert not unjudged
    else:  # its HistoricData's inline EstimatedState cannot be read: not judged, never FAIL (a scenario's window
        # may end before a frame of it in the recording that the live run saw: those cases are not compared)
        assert unjudged and all(k.startswith("imc/HistoricData/") and v == "INCONCLUSIVE" for k, v in unjudged.items())
        assert Verdict.FAIL.value not in alike.values()
        judged = {k: v for k, v in judged.items() if k not in unjudged}
        alike = {k: v for k, v in alike.items() if k not in unjudged and v != "INCONCLUSIVE"}
    assert {k: v for k, v in judged.items() if "/capture/" not in k} == alike
    named = "EstimatedState" if whole_xml == "cached" else "id 350"  # named as the whole IMC.xml names it
    assert any(f"{named} (" in n and "does not cover" in n for n in doc["notes"])
    assert any("id 999 (" in n and "no definition" in n for n in doc["notes"])


def test_a_log_with_that_traffic_is_judged_alike(suite, tmp_path, capsys):
    fetched_whole_xml()  # its HistoricData's inline EstimatedState is read with it
    node = ReferenceNode(suite.defs, suite.behaviour, edition="imc-5.4.30", address=NODE, variant=TRAFFIC)
    heartbeat = codec.encode(suite.defs, {"abbrev": "Heartbeat", "fields": {}, "header": {
        "timestamp": 1.7e9, "src": 30, "src_ent": 0, "dst": 0xFFFF, "dst_ent": 0xFF}})
    (tmp_path / "Data.lsf").write_bytes(b"".join(node._traffic(1.0) + [heartbeat]))
    assert main(["log", str(tmp_path / "Data.lsf"), "--json", str(tmp_path / "log.json")]) == 0
    doc = json.loads((tmp_path / "log.json").read_text())
    assert [c["verdict"] for m in doc["messages"] for c in m["cases"]] == ["PASS", "PASS"]  # HistoricData, Heartbeat
    assert any("Temperature (1)" in n for n in doc["notes"]) and any("id 999 (1)" in n for n in doc["notes"])


@pytest.mark.parametrize("order", ["<", ">"])
def test_the_wire_tells_other_traffic_from_a_broken_frame_in_either_byte_order(suite, order):
    fetched_whole_xml()  # which names the messages outside the suite
    wire, defs = suite.wire, suite.defs
    other = wire.parse(sound(defs, 350, bytes(88), order))
    assert (other.outside, other.undefined, other.problem, other.decoded) == ("EstimatedState", False, None, None)
    assert wire.parse(sound(defs, 999, b"\x01", order)).undefined
    damaged = bytearray(sound(defs, 350, bytes(88), order))
    damaged[-1] ^= 1
    assert wire.parse(bytes(damaged)).problem.startswith("crc") and wire.parse(bytes(damaged)).outside is None
    null = wire.parse(sound(defs, defs.null_id, b"", order))
    assert null.problem.startswith("unknown-id") and null.outside is None  # the null id names no message at all


def test_watch_judges_that_traffic_alike(suite):
    """What ``watch`` does with each datagram its socket receives (``CaptureJudge.received``)."""
    fetched_whole_xml()  # its HistoricData's inline EstimatedState is read with it
    from imc_conformance.capture.datagrams import Datagram
    from imc_conformance.capture.judge import CaptureJudge, Selection

    node = ReferenceNode(suite.defs, suite.behaviour, edition="imc-5.4.30", address=NODE, variant=TRAFFIC)
    judge = CaptureJudge("imc", suite.capture_rules(), "imc-5.4.30", Selection(frozenset([6001])))
    for i, payload in enumerate(node._traffic(0.0)):
        judge.received(Datagram(i + 1, 1.7e9 + i, "127.0.0.1", 6002, "127.0.0.1", 6001, payload))
    result = judge.result(implementation="watch", started="", duration=0.0, strict=True, title="watch")
    assert result.exit_code() == 0 and {c.verdict for c in result.cases} == {Verdict.PASS}  # its HistoricData alone
    assert any("EstimatedState (1)" in n and "does not cover" in n for n in result.notes)
    assert any("id 999 (1)" in n and "never a failure" in n for n in result.notes)


def historic(defs, inner_id: int = 350, inner: bytes = bytes(88), e: str = "<") -> bytes:
    """A HistoricData as a DUNE vehicle's data store sends it: one HistoricSample holding message ``inner_id``."""
    sample = struct.pack(e + "HHbhhhhH", defs["HistoricSample"].id, 30, 0, 1, 2, 3, 4, inner_id) + inner
    return sound(defs, defs["HistoricData"].id, struct.pack(e + "fffH", 0.7, -0.15, 100.0, 1) + sample, e)


@pytest.fixture(params=["cached", "absent"])
def whole_xml(request, monkeypatch, tmp_path):
    """Whether the whole IMC.xml is in the cache: fetched into the suite's cache, or absent (an empty cache folder of
    the test's own)."""
    if request.param == "absent":
        monkeypatch.setenv("IMC_CONFORMANCE_CACHE", str(tmp_path / "cache"))
    else:
        fetched_whole_xml()
    return request.param


@pytest.mark.parametrize("order", ["<", ">"])
def test_an_inline_message_outside_the_suite_is_read_with_the_whole_protocol(suite, whole_xml, order):
    parsed = suite.wire.parse(historic(suite.defs, e=order))
    if whole_xml == "cached":
        assert parsed.problem is None and parsed.message == "HistoricData"
        assert parsed.decoded["fields"]["data"][0]["fields"]["sample"]["abbrev"] == "EstimatedState"
    else:
        assert parsed.undecided and "the whole IMC.xml is not in the cache" in parsed.problem
    listed = struct.pack(order + "fffH", 0.7, -0.15, 100.0, 2) + struct.pack(order + "H", 350) + bytes(88) + struct.pack(
        order + "HB", 7, 12)  # message-list elements outside the suite: an EstimatedState, a CpuUsage
    elements = suite.wire.parse(sound(suite.defs, suite.defs["HistoricData"].id, listed, order))
    if whole_xml == "cached":
        assert [m["abbrev"] for m in elements.decoded["fields"]["data"]] == ["EstimatedState", "CpuUsage"]
    else:
        assert elements.undecided and "data[0] holds message id 350" in elements.problem
    undefined = suite.wire.parse(historic(suite.defs, 999, b"", order))  # no IMC.xml has it: the rest cannot be read
    assert undefined.undecided and undefined.problem.startswith("inline-outside-definitions")
    broken = suite.wire.parse(historic(suite.defs, 350, bytes(80), order))  # an EstimatedState 8 bytes short
    assert broken.undecided if whole_xml == "absent" else broken.problem.startswith("field-overrun")
    with pytest.raises(Exception, match="unknown-inline-id|holds unknown message id 350"):  # the corpus's rule stays
        codec.decode(suite.defs, historic(suite.defs, e=order))


def test_a_log_and_watch_judge_such_a_historic_data_alike(suite, whole_xml, tmp_path):
    from imc_conformance.capture.datagrams import Datagram
    from imc_conformance.capture.judge import CaptureJudge, Selection

    frames = {"vehicle": historic(suite.defs), "undefined": historic(suite.defs, 999, b""),
              "broken": historic(suite.defs, 350, bytes(80))}
    expected = {"vehicle": "PASS" if whole_xml == "cached" else "INCONCLUSIVE", "undefined": "INCONCLUSIVE",
                "broken": "FAIL" if whole_xml == "cached" else "INCONCLUSIVE"}
    for name, frame in frames.items():
        (tmp_path / f"{name}.lsf").write_bytes(frame)
        code = main(["log", str(tmp_path / f"{name}.lsf"), "--json", str(tmp_path / f"{name}.json")])
        doc = json.loads((tmp_path / f"{name}.json").read_text())
        verdicts = {c["verdict"] for m in doc["messages"] for c in m["cases"]}
        assert verdicts == {expected[name]} and (code == 1) == (expected[name] == "FAIL"), (name, verdicts, doc["notes"])
        judge = CaptureJudge("imc", suite.capture_rules(), "imc-5.4.30", Selection(frozenset([6001])))
        judge.received(Datagram(1, 1.7e9, "127.0.0.1", 6002, "127.0.0.1", 6001, frame))
        result = judge.result(implementation="watch", started="", duration=0.0, strict=True, title="watch")
        assert {c.verdict.value for c in result.cases} == {expected[name]}, name


def test_without_the_whole_imc_xml_that_traffic_is_not_judged_never_failed(suite, cases, monkeypatch, tmp_path):
    monkeypatch.setenv("IMC_CONFORMANCE_CACHE", str(tmp_path / "cache"))  # an empty cache: no IMC.xml to read it with
    result, _ = run_virtual(suite, cases, "imc-5.4.30", kinds=("scenario", "robustness"), variant=TRAFFIC, strict=True)
    unjudged = {c.id: c.detail for c in result.cases if c.verdict == Verdict.INCONCLUSIVE}
    assert Verdict.FAIL not in {c.verdict for c in result.cases} and unjudged
    assert all(k.startswith("imc/HistoricData/passive/") and "the whole IMC.xml is not in the cache" in d
               for k, d in unjudged.items())
