"""A run's exchange saved as pcapng (run --pcap) and judged again by the pcap command: the scenario engine
replayed over the recording gives the live run's verdicts, the passive exchange rules catch the broken nodes
that break them, and tshark reads the file with its comments. Everything on virtual time."""

from __future__ import annotations

import json
import shutil
import subprocess

import pytest

from imc_conformance.capture.datagrams import Dissector
from imc_conformance.capture.recording import ABOUT, Recorder, about_run
from imc_conformance.capture.records import records
from imc_conformance.capture.writing import PCAP_HEADER, PcapNgWriter, pcap_record
from imc_conformance.cli import main
from imc_conformance.files import open_corpus
from imc_conformance.suites import load_suite
from imc_conformance.suites.imc import codec
from imc_conformance.suites.imc.node.breaks import BREAKS

from live_harness import EVERYTHING, run_virtual

EDITION = "imc-5.4.30"
HEARTBEAT_FRAME = codec.encode(load_suite("imc").defs, {"abbrev": "Heartbeat", "fields": {}, "header": {
    "timestamp": 1.0, "src": 0xA0, "src_ent": 1, "dst": 0x4CF0, "dst_ent": 255}})
# the broken nodes the passive exchange rules must catch, with the case that catches each
PASSIVE = {
    "req-id-not-echoed": "imc/AcousticRequest/capture/exchange/acoustic-request/echo-req_id",
    "type-not-echoed": "imc/AcousticRequest/capture/exchange/acoustic-request/echo-type",
    "status-after-terminal": "imc/AcousticRequest/capture/exchange/acoustic-request/after-terminal",
    "two-terminals": "imc/AcousticRequest/capture/exchange/acoustic-request/after-terminal",
    "no-terminal": "imc/AcousticRequest/capture/exchange/acoustic-request/terminal",
    "broadcast-replies": "imc/AcousticRequest/capture/exchange/acoustic-request/to-requester",
    "no-cur-cfg": "imc/LblConfig/capture/exchange/lbl-configuration/answered",
    "seq-not-echoed": "imc/SmsTx/capture/exchange/sms-transmission/echo-seq",
}


@pytest.fixture(scope="module")
def corpus():
    return open_corpus("imc")


def record(corpus, path, **node):
    """Run the scenarios on virtual time, recording to ``path``; the live result."""
    suite, everything = corpus
    options = dict(EVERYTHING, time_scale=1.0, profile=suite.profile("seed"))
    ids = [c.id for c in everything if c.kind == "scenario"]
    recorder = Recorder(path, about_run("imc", EDITION, ids, options, "udp://127.0.0.1:6002", None, None, 10.0))
    try:
        result, _ = run_virtual(suite, everything, edition=EDITION, options=options, recorder=recorder, **node)
    finally:
        recorder.close(complete=True)
    return result


def judged(path, tmp_path, *argv):
    out = tmp_path / "judged.json"
    code = main(["pcap", str(path), "--json", str(out), *argv])
    return code, json.loads(out.read_text())


def verdicts(doc_or_result, part: str) -> dict:
    if isinstance(doc_or_result, dict):
        items = [(c["id"], c["verdict"]) for m in doc_or_result["messages"] for c in m["cases"]]
    else:
        items = [(c.id, c.verdict.value) for c in doc_or_result.cases]
    return {k: v for k, v in items if part in k}


@pytest.mark.parametrize("node", [{}, {"loss": 0.1, "dup": 0.05, "seed": 3}, *({"broken": b} for b in sorted(BREAKS))],
                         ids=lambda n: "-".join(str(v) for v in n.values()) or "reference")
def test_the_replay_gives_the_live_verdicts(node, corpus, tmp_path):
    path = tmp_path / "run.pcapng"
    live = record(corpus, path, **node)
    code, doc = judged(path, tmp_path)
    scenario = verdicts(live, "/scenario/") | verdicts(live, "/passive/")
    assert scenario and verdicts(doc, "/scenario/") | verdicts(doc, "/passive/") == scenario
    if not node:
        assert code == 0 and set(verdicts(doc, "/capture/").values()) <= {"PASS", "IMPL_DEFINED"}  # BUSY: a reading
    if node.get("broken") in PASSIVE:
        assert verdicts(doc, "/capture/").get(PASSIVE[node["broken"]]) in ("FAIL", "NON_STRICT"), node
    if "loss" in node:  # a request lost on the way goes unanswered in the capture; duplicates are judged once
        failed = {k.rsplit("/", 1)[1] for k, v in verdicts(doc, "/capture/").items() if v not in ("PASS", "IMPL_DEFINED")}
        assert failed == {"answered"} and any("duplicated by the network" in n for n in doc["notes"])


def test_without_comments_only_the_passive_rules_apply(corpus, tmp_path):
    path = tmp_path / "run.pcapng"
    record(corpus, path, broken="req-id-not-echoed")
    plain = tmp_path / "plain.pcap"  # the same datagrams, as classic pcap (raw IP), no comments
    plain.write_bytes(PCAP_HEADER[:20] + (101).to_bytes(4, "little") + b"".join(
        pcap_record(r.time, r.data) for r in records(path.read_bytes())))
    code, doc = judged(plain, tmp_path)
    assert code == 1 and not verdicts(doc, "/scenario/")
    assert verdicts(doc, "/capture/")[PASSIVE["req-id-not-echoed"]] == "FAIL"


def test_a_damaged_run_description_is_one_line(corpus, tmp_path, capsys):
    path = tmp_path / "run.pcapng"
    record(corpus, path)
    data = path.read_bytes().replace(b'"cases": [', b'"casez": [', 1)  # the same length: the blocks stay whole
    path.write_bytes(data)
    assert main(["pcap", str(path), "--json", str(tmp_path / "r.json")]) == 2
    err = capsys.readouterr().err
    assert "the recorded run's description is damaged: cases is not a list; its frames and exchanges are judged" in err
    assert "Traceback" not in err
    doc = json.loads((tmp_path / "r.json").read_text())
    assert not [c for m in doc["messages"] for c in m["cases"] if "/scenario/" in c["id"]]
    assert any(c["id"].endswith("/capture/frame/valid") for m in doc["messages"] for c in m["cases"])


@pytest.mark.skipif(shutil.which("tshark") is None, reason="tshark is not installed (.ci/run installs Debian's)")
def test_tshark_reads_the_recording_with_its_comments(corpus, tmp_path):
    path = tmp_path / "run.pcapng"
    record(corpus, path)
    ours = list(records(path.read_bytes()))
    done = subprocess.run(["tshark", "-r", str(path), "-T", "fields", "-e", "frame.number", "-e", "frame.comment",
                           "-e", "udp.srcport", "-e", "udp.dstport"], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    rows = [line.split("\t") for line in done.stdout.splitlines()]
    assert len(rows) == len(ours) > 100
    assert [(int(n), c) for n, c, *_ in rows] == [(r.number, r.comment) for r in ours]
    assert {row[2] for row in rows} == {"6001", "6002"} and any("/scenario/" in row[1] for row in rows)


@pytest.mark.parametrize("argv, message", [
    (["--adapter", "imcpy", "--pcap", "run.pcapng"], "--pcap records a live run's datagrams: give --target"),
    (["--target", "udp://127.0.0.1:9", "--pcap", "/proc/no/run.pcapng"], "cannot write the pcapng to /proc/no/run.pcapng"),
])
def test_a_recording_that_cannot_be_made_is_one_line(argv, message, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["run", *argv]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1


def test_an_interrupted_recording_replays_only_what_finished(corpus, tmp_path):
    whole = tmp_path / "run.pcapng"
    live = record(corpus, whole)
    sections: list[str] = []
    kept = list(records(whole.read_bytes(), sections))
    half = tmp_path / "half.pcapng"  # the first 20 s, as a run stopped there leaves it (no closing comment)
    with half.open("wb") as handle:
        writer = PcapNgWriter(handle, sections[0])
        for r in kept:
            if r.time - kept[0].time <= 20:
                d = Dissector().datagram(r)
                writer.write(r.time, (d.src, d.sport), (d.dst, d.dport), d.payload, r.comment)
    code, doc = judged(half, tmp_path)
    replayed = verdicts(doc, "/scenario/")
    before = verdicts(live, "/scenario/")
    assert 0 < len(replayed) < len(before) and all(before[k] == v for k, v in replayed.items())
    assert any(n.startswith("the recording ends before its run did") for n in doc["notes"])
    assert code == 0


def test_a_robustness_recording_judges_the_node_not_the_sessions_own_frames(corpus, tmp_path):
    suite, everything = corpus
    options = dict(EVERYTHING, time_scale=1.0, profile=suite.profile("seed"))
    ids = [c.id for c in everything if c.kind == "scenario"]
    path = tmp_path / "rob.pcapng"
    recorder = Recorder(path, about_run("imc", EDITION, ids, options, "udp://127.0.0.1:6002", None, None, 10.0))
    try:
        live, _ = run_virtual(suite, everything, edition=EDITION, options=options, recorder=recorder,
                              kinds=("scenario", "robustness"))
    finally:
        recorder.close(complete=True)
    code, doc = judged(path, tmp_path)
    assert set(verdicts(live, "").values()) <= {"PASS", "IMPL_DEFINED"}  # IMPL_DEFINED: open readings (BUSY)
    assert code == 0 and set(verdicts(doc, "/capture/").values()) <= {"PASS", "IMPL_DEFINED"}
    assert any("datagrams the session sent on purpose in its robustness phase" in n for n in doc["notes"])
    assert verdicts(doc, "/scenario/") == verdicts(live, "/scenario/")


@pytest.mark.parametrize("change", [{"time_scale": float("inf")}, {"time_scale": 1e300}, {"time_scale": 0},
                                    {"startup": float("nan")}, {"src": 70000}, {"params": []}, {"edition": 5},
                                    {"suite": "nope"}, {"profile": "nope"}, {"claims": "acoustic"}, {"cases": [1]}])
def test_a_hostile_run_description_is_refused_and_the_frames_still_judged(change, tmp_path, capsys):
    about = about_run("imc", EDITION, ["imc/Heartbeat/scenario/alive"], {"profile": {"name": "seed"}},
                      "udp://127.0.0.1:6002", None, None, 10.0) | change
    path = tmp_path / "hostile.pcapng"
    with path.open("wb") as handle:
        writer = PcapNgWriter(handle, ABOUT + json.dumps(about))
        writer.write(1.7e9, ("127.0.0.1", 6002), ("127.0.0.1", 6001), HEARTBEAT_FRAME, "received")
    code = main(["pcap", str(path), "--json", str(tmp_path / "r.json")])
    err = capsys.readouterr().err
    assert code == 2 and "Traceback" not in err
    assert "cannot be replayed" in err or "description is damaged" in err
    doc = json.loads((tmp_path / "r.json").read_text())
    assert [c["id"] for m in doc["messages"] for c in m["cases"]] == ["imc/Heartbeat/capture/frame/valid"]


def test_a_dry_run_records_nothing(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["run", "--target", "udp://127.0.0.1:9", "--dry-run", "--pcap", "dry.pcapng"]) == 2
    assert "--dry-run sends nothing" in capsys.readouterr().err


def test_a_long_run_description_is_written_and_read_back(tmp_path):
    from imc_conformance.capture.recording import read_about

    about = about_run("imc", EDITION, [f"imc/Heartbeat/scenario/{i}" for i in range(5000)],
                      {"profile": {"name": "seed"}}, "udp://127.0.0.1:6002", None, None, 10.0)
    path = tmp_path / "long.pcapng"
    with path.open("wb") as handle:  # over 65,535 bytes: one pcapng option cannot hold it
        PcapNgWriter(handle, ABOUT + json.dumps(about)).write(1.7e9, ("127.0.0.1", 6002), ("127.0.0.1", 6001),
                                                              HEARTBEAT_FRAME, "received")
    sections: list[str] = []
    assert len(list(records(path.read_bytes(), sections))) == 1
    assert read_about(sections) == about


def test_a_recorded_parameter_the_live_run_would_refuse_is_not_replayed(tmp_path, capsys):
    about = about_run("imc", EDITION, ["imc/Heartbeat/scenario/alive"], {"profile": {"name": "seed"},
                      "params": {"peer": "x" * 70000}}, "udp://127.0.0.1:6002", None, None, 10.0)
    path = tmp_path / "p.pcapng"
    with path.open("wb") as handle:
        PcapNgWriter(handle, ABOUT + json.dumps(about)).write(1.7e9, ("127.0.0.1", 6002), ("127.0.0.1", 6001),
                                                              HEARTBEAT_FRAME, "received")
    assert main(["pcap", str(path)]) == 2
    assert "the recorded run cannot be replayed: --param peer=" in capsys.readouterr().err
