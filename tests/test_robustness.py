"""The robustness phase (--robustness) against the reference node and broken ones, on virtual time: every corpus
frame, then 10,000 garbage datagrams; every request kind answered before must still be answered, and a node that
stops answering is named with the block and, when it can be restarted, the frame that did it."""

from __future__ import annotations

import json

import pytest

from imc_conformance.core.verdicts import Verdict
from imc_conformance.render import RENDERERS
from live_harness import EVERYTHING, PARAMS, run_virtual

ROBUSTNESS = ("robustness",)
ACOUSTIC = ("imc/AcousticRequest/robustness/still-served", "imc/AcousticOperation/robustness/still-served")


def by_id(result):
    return {c.id: c for c in result.cases}


@pytest.fixture(scope="module")
def reference(suite, cases):
    return run_virtual(suite, cases, kinds=ROBUSTNESS, restartable=True)


def test_the_reference_node_survives_every_frame_and_the_garbage(reference, cases):
    result, link = reference
    probes = [c for c in cases if c.kind == "robustness"]
    assert len(probes) == 8 and {c.id for c in result.cases} == {c.id for c in probes}
    assert {c.id: c.detail for c in result.cases if c.verdict is not Verdict.PASS} == {}
    for case in result.cases:
        assert [k.check for k in case.checks] == ["baseline", "corpus", "garbage"]
    assert result.exit_code() == 0 and link.restarts == 0
    sent = len(link.sent)
    assert sent > 4500 + 10000  # every frame that fits a datagram, then the garbage


def test_frames_are_readdressed_with_their_defects_kept(suite, reference):
    _, link = reference
    parsed = [suite.wire.parse(d) for d in link.sent]
    problems = [p.problem for p in parsed if p.problem]
    assert any(p.startswith("crc ") for p in problems) and any(p.startswith("sync ") for p in problems)
    valid = [p for p in parsed if p.decoded is not None and p.decoded["header"]["src_ent"] == 254]
    assert valid and all(p.decoded["header"]["dst"] == 0x00A0 for p in valid)  # the node's id, learned


def test_a_node_silenced_by_one_valid_frame_is_named_and_bisected(suite, cases):
    result, link = run_virtual(suite, cases, kinds=ROBUSTNESS, restartable=True, broken="dies-after-raw")
    found = by_id(result)
    for case_id in ACOUSTIC:
        case = found[case_id]
        assert case.verdict is Verdict.FAIL
        assert "after block" in case.detail and "bisected: the frame imc/AcousticRequest/" in case.detail
        assert "RAW" in case.detail.split("bisected:")[1] or "raw" in case.detail.split("bisected:")[1]
    assert all(c.verdict is Verdict.PASS for c in result.cases if c.id not in ACOUSTIC)
    assert 3 <= link.restarts <= 12 and result.exit_code() == 1
    assert any(e["event"] == "bisect" for e in found[ACOUSTIC[0]].timeline)


def test_without_a_restart_command_the_block_is_named(suite, cases):
    result, link = run_virtual(suite, cases, kinds=ROBUSTNESS, broken="dies-after-raw")
    case = by_id(result)[ACOUSTIC[0]]
    assert case.verdict is Verdict.FAIL and "give --restart-cmd to bisect" in case.detail and link.restarts == 0


def test_a_node_that_dies_of_garbage_is_caught_after_the_garbage(suite, cases):
    result, _ = run_virtual(suite, cases, kinds=ROBUSTNESS, broken="leaks-on-drop")
    found = by_id(result)
    assert found["imc/Heartbeat/robustness/still-served"].verdict is Verdict.PASS  # its heartbeat goes on
    failed = {c.id for c in result.cases if c.verdict is Verdict.FAIL}
    assert failed == set(found) - {"imc/Heartbeat/robustness/still-served"}
    check = next(k for k in found["imc/LblConfig/robustness/still-served"].checks if k.check == "garbage")
    assert check.verdict is Verdict.FAIL and "garbage" in check.detail


def test_a_kind_not_served_before_is_inconclusive(suite, cases):
    result, _ = run_virtual(suite, cases, kinds=ROBUSTNESS, broken="no-cur-cfg")
    case = by_id(result)["imc/LblConfig/robustness/still-served"]
    assert case.verdict is Verdict.INCONCLUSIVE and "before the robustness phase" in case.detail


def test_malformed_replies_during_the_phase_fail_their_message(suite, cases):
    result, _ = run_virtual(suite, cases, kinds=ROBUSTNESS, broken="malformed-reply")
    passive = [c for c in result.cases if c.id.startswith("imc/AcousticSystems/passive/")]
    assert passive and all(c.verdict is Verdict.FAIL for c in passive)
    assert result.exit_code() == 1


def test_effects_not_allowed_keep_their_frames_and_probes_out(suite, cases):
    result, link = run_virtual(suite, cases, kinds=ROBUSTNESS, options={"params": PARAMS})
    ran = {c.id for c in result.cases}
    assert ran == {"imc/Heartbeat/robustness/still-served", "imc/AcousticSystemsQuery/robustness/still-served",
                   "imc/LblConfig/robustness/still-served", "imc/HistoricDataQuery/robustness/still-served"}
    assert any("effects not allowed" in n for n in result.notes)
    corpus = next(k for k in result.cases[0].checks if k.check == "corpus")
    assert "accepted frames of AcousticOperation, AcousticRequest (effects not allowed" in corpus.detail
    sent = [suite.wire.parse(d) for d in link.sent]
    assert not any(p.message == "IridiumMsgTx" and p.decoded is not None for p in sent)


def test_the_phase_runs_only_when_asked(suite, cases):
    result, link = run_virtual(suite, cases, kinds=ROBUSTNESS, options=dict(EVERYTHING, robustness=False))
    assert result.cases == [] and any("only with --robustness" in n for n in result.notes)
    assert len(link.sent) < 100


def test_reruns_are_identical_and_every_renderer_shows_the_verdict(suite, cases):
    first, _ = run_virtual(suite, cases, kinds=ROBUSTNESS, broken="dies-after-raw", restartable=True)
    again, _ = run_virtual(suite, cases, kinds=ROBUSTNESS, broken="dies-after-raw", restartable=True)
    assert json.dumps(first.to_dict(), sort_keys=True) == json.dumps(again.to_dict(), sort_keys=True)
    for fmt, render in RENDERERS.items():
        assert "still-served" in render(first), fmt
