"""A run's exchange saved as pcapng (run --pcap) and judged again by the pcap command: the scenario engine
replayed over the recording gives the live run's verdicts, the passive exchange rules catch the broken nodes
that break them, and tshark reads the file with its comments. Everything on virtual time."""

from __future__ import annotations

import json
import shutil
import subprocess

import pytest

from imc_conformance.capture.recording import Recorder, about_run
from imc_conformance.capture.records import records
from imc_conformance.capture.writing import PCAP_HEADER, pcap_record
from imc_conformance.cli import main
from imc_conformance.files import open_corpus
from imc_conformance.suites.imc.node.breaks import BREAKS

from live_harness import EVERYTHING, run_virtual

EDITION = "imc-5.4.30"
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
        recorder.close()
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
        assert code == 0 and set(verdicts(doc, "/capture/").values()) == {"PASS"}
    if node.get("broken") in PASSIVE:
        assert verdicts(doc, "/capture/").get(PASSIVE[node["broken"]]) in ("FAIL", "NON_STRICT"), node
    if "loss" in node:  # a request lost on the way goes unanswered in the capture; duplicates are judged once
        failed = {k.rsplit("/", 1)[1] for k, v in verdicts(doc, "/capture/").items() if v != "PASS"}
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
    assert main(["pcap", str(path)]) == 2
    err = capsys.readouterr().err
    assert "the recorded run's description is damaged: no list of cases" in err and "Traceback" not in err


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
