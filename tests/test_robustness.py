"""The robustness phase (--robustness) against the reference node and broken ones, on virtual time: every corpus
frame, then 10,000 garbage datagrams; every request kind answered before must still be answered, and a node that
stops answering is named with the block and, when it can be restarted, the frame that did it."""

from __future__ import annotations

import json
import random
from collections import Counter

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


def test_the_reference_node_survives_every_frame_and_the_garbage(suite, reference, cases):
    result, link = reference
    probes = [c for c in cases if c.kind == "robustness"]
    assert len(probes) == 8 and {c.id for c in result.cases} == {c.id for c in probes}
    assert {c.id: c.detail for c in result.cases if c.verdict is not Verdict.PASS} == {}
    for case in result.cases:
        assert [k.check for k in case.checks] == ["probe:baseline", "probe:corpus", "probe:hostile", "probe:garbage"]
        assert "after each of the 8 hostile blocks" in case.checks[2].detail
    assert result.exit_code() == 0 and link.restarts == 0
    phase = suite.kinds["robustness"].phase(suite.editions[0], {"corpus": tuple(c for c in cases if c.kind == "vector"),
                                                                "replay_effects": True})
    settings = suite.behaviour["robustness"]
    flood = [suite.wire.readdress(f.data, f.encoding, (0x4CF0, 254), 0x00A0) for f in phase.frames]
    flood += suite.wire.garbage(random.Random(settings["seed"]), settings["garbage"], (0x4CF0, 254), 0x00A0)
    assert len(flood) >= 3600 + 10000
    assert Counter(d for d in link.sent if d in set(flood)) == Counter(flood)  # one phase: every datagram once


def test_frames_are_readdressed_with_their_defects_kept(suite, cases, reference):
    """Every replayed frame is the corpus frame with the session's src and the node's dst, and the reference codec
    judges it as the case says: a valid frame still decodes, an invalid one still breaks the case's rule."""
    _, link = reference
    by_id = {c.id: c.data for c in cases}
    phase = suite.kinds["robustness"].phase(suite.editions[0], {"corpus": tuple(c for c in cases if c.kind == "vector"),
                                                                "replay_effects": True})
    replayed = [data for data in link.sent if len(data) < 20 or data[16] == 254 or suite.wire.parse(data).decoded is None]
    expected = [suite.wire.readdress(f.data, f.encoding, (0x4CF0, 254), 0x00A0) for f in phase.frames]
    assert replayed[:len(expected)] == expected  # in corpus order, before the garbage
    for frame, data in zip(phase.frames, expected):
        parsed = suite.wire.parse(data)
        if frame.expect == "valid":
            assert parsed.decoded is not None and parsed.decoded["header"]["dst"] == 0x00A0, frame.case_id
        elif frame.expect == "invalid" and parsed.outside is not None:  # a sound frame of an id nothing defines:
            assert by_id[frame.case_id]["rule"] == "unknown-id" and parsed.undefined  # a decoder refuses it, a
            # live link counts it as another system's traffic, judged no further
        elif frame.expect == "invalid" and parsed.undecided:  # an inline id no IMC.xml defines: the rest of the
            assert by_id[frame.case_id]["rule"] == "unknown-inline-id", frame.case_id  # frame is unreadable, not judged
        elif frame.expect == "invalid":
            assert parsed.problem and parsed.problem.startswith(by_id[frame.case_id]["rule"] + " "), frame.case_id


def test_a_node_silenced_by_one_valid_frame_is_named_and_bisected(suite, cases):
    result, link = run_virtual(suite, cases, kinds=ROBUSTNESS, restartable=True, broken="dies-after-raw")
    found = by_id(result)
    for case_id in ACOUSTIC:
        case = found[case_id]
        assert case.verdict is Verdict.FAIL
        assert "after block" in case.detail and "bisected: the frame imc/AcousticRequest/" in case.detail
        assert "RAW" in case.detail.split("bisected:")[1] or "raw" in case.detail.split("bisected:")[1]
    assert all(c.verdict is Verdict.PASS for c in result.cases if c.id not in ACOUSTIC)
    # the corpus holds two valid RAW requests, in two blocks: each block is bisected (about log2(200) restarts), the
    # node is restarted to go on, and once more at the end to leave it fresh
    assert found[ACOUSTIC[0]].detail.count("bisected: the frame imc/AcousticRequest/") == 2
    assert 15 <= link.restarts <= 25 and result.exit_code() == 1
    assert any(e["event"] == "bisect" for e in found[ACOUSTIC[0]].timeline)


class SlowAcousticStart:
    """A node whose acoustic service comes up ``warmup`` seconds after a restart (DUNE's does: its acoustic tasks
    and modem start after its UDP transport); until then acoustic requests go unanswered."""

    def __init__(self, node, born: float, wire, warmup: float = 15.0):
        self.node, self.ready, self.wire = node, born + warmup, wire

    @property
    def deadline(self):
        return self.node.deadline

    def due(self, t):
        return self.node.due(t)

    def receive(self, t, data, source):
        decoded = self.wire.parse(data).decoded
        if t < self.ready and decoded and decoded["abbrev"] in ("AcousticOperation", "AcousticRequest"):
            return
        self.node.receive(t, data, source)


def test_a_node_slow_to_serve_after_a_restart_is_still_bisected(suite, cases):
    """The restarted node is asked again until the robustness settings' revive bound, not just a probe's tries."""
    assert suite.behaviour["robustness"]["revive"] > 15.0 > 2 * 5  # longer than two tries of the acoustic probes
    result, link = run_virtual(suite, cases, kinds=ROBUSTNESS, restartable=True, broken="dies-after-raw",
                               restarted=lambda node, t: SlowAcousticStart(node, t, suite.wire))
    case = by_id(result)[ACOUSTIC[1]]
    assert case.verdict is Verdict.FAIL and case.detail.count("bisected: the frame imc/AcousticRequest/") == 2
    assert "did not serve the probe again" not in case.detail
    assert any("after a restart, before bisecting further: AcousticOperation received (try 4)" in e.get("note", "")
               for e in case.timeline)


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
    check = next(k for k in found["imc/LblConfig/robustness/still-served"].checks if k.check == "probe:garbage")
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


def test_effects_not_allowed_keep_their_probes_out_and_effectful_frames_need_their_own_opt_in(suite, cases):
    result, link = run_virtual(suite, cases, kinds=ROBUSTNESS, options={"params": PARAMS})
    ran = {c.id for c in result.cases}
    assert ran == {"imc/Heartbeat/robustness/still-served", "imc/AcousticSystemsQuery/robustness/still-served",
                   "imc/LblConfig/robustness/still-served", "imc/HistoricDataQuery/robustness/still-served"}
    assert any("effects not allowed" in n for n in result.notes)
    # even with every effect allowed for the probes, the corpus's own destinations are not replayed unless asked
    for options, replayed in ((dict(EVERYTHING, replay_effects=False), False), (dict(EVERYTHING, replay_effects=True), True)):
        result, link = run_virtual(suite, cases, kinds=ROBUSTNESS, options=options)
        corpus = next(k for k in result.cases[0].checks if k.check == "probe:corpus")
        assert ("accepted frames of AcousticOperation, AcousticRequest (transmits-acoustically, aborts; "
                "--replay-effects replays them)" in corpus.detail) is not replayed
        numbers = {str(p.fields["destination"]) for p in map(suite.wire.parse, link.sent)
                   if p.message == "SmsTx" and p.decoded is not None}
        assert bool(numbers - {PARAMS["sms_number"]}) is replayed  # the corpus's numbers, beside the probe's


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


def test_live_results_are_valid_result_documents_that_report_reads_back(suite, cases, tmp_path, capsys):
    from imc_conformance.cli import main
    from imc_conformance.files import read_result

    for kinds in (("scenario",), ("robustness",)):
        result, _ = run_virtual(suite, cases, kinds=kinds, broken="two-terminals", restartable=True)
        path = tmp_path / f"{kinds[0]}.json"
        path.write_text(json.dumps(result.to_dict()))
        assert read_result(path).to_dict() == result.to_dict()
        assert main(["report", str(path), "--html", str(tmp_path / "r.html")]) == result.exit_code()


def test_a_restart_that_does_not_restore_the_service_stops_the_bisection(suite, cases):
    from imc_conformance.core.runner import run_cases
    from live_harness import scenario_cases, virtual_session

    session, link = virtual_session(suite, suite.editions[0], restartable=True, broken="dies-after-raw")
    session.restart = lambda: None  # "restarted", but the same silenced node goes on
    options = dict(EVERYTHING, corpus=tuple(c for c in cases if c.kind == "vector"), robustness=True, restart=True,
                   replay_effects=True)
    result = run_cases(session, suite, scenario_cases(cases, kinds=ROBUSTNESS), edition=suite.editions[0],
                       adapter="virtual", options=options, clock=link.now)
    case = by_id(result)[ACOUSTIC[0]]
    assert case.verdict is Verdict.FAIL and "not bisected: after a restart the node did not serve" in case.detail


@pytest.mark.parametrize("broken, silenced, block", [("dies-on-own-id", ACOUSTIC, "from-own-id"),
                                                     ("exhausted-by-many", None, "many-at-once")])
def test_a_node_silenced_by_everyday_traffic_names_the_hostile_block(suite, cases, broken, silenced, block):
    """Valid requests of the kinds UDP brings every day (addressed elsewhere, from the node's own id or an unannounced
    system, duplicated, reusing one id, many at once): a node they silence fails the probes, naming the block."""
    result, link = run_virtual(suite, cases, kinds=ROBUSTNESS, restartable=True, broken=broken)
    failed = {c.id: c for c in result.cases if c.verdict is Verdict.FAIL}
    assert failed and (silenced is None or set(failed) == set(silenced))
    for case in failed.values():
        hostile = next(k for k in case.checks if k.check == "probe:hostile")
        assert hostile.verdict is Verdict.FAIL and f"after the hostile block {block} (" in hostile.detail
        assert next(k for k in case.checks if k.check == "probe:corpus").verdict is Verdict.PASS
    assert link.restarts >= 1  # brought back to go on, and left as it was found


def test_the_hostile_blocks_send_what_their_kinds_say(suite, cases, reference):
    _, link = reference
    flood = [suite.wire.parse(d).decoded for d in link.sent]
    flood = [d for d in flood if d is not None and d["header"]["src_ent"] == 254 and d["abbrev"] != "Announce"]
    node = 0x00A0
    dsts = Counter(d["header"]["dst"] for d in flood if d["header"]["src"] == 0x4CF0)
    assert dsts[0xFFFF] and dsts[0] and any(dst not in (0, 0xFFFF, node) for dst in dsts)
    assert any(d["header"]["src"] == node for d in flood)  # from the node's own id
    assert any(d["header"]["src"] not in (0x4CF0, node) and d["header"]["dst"] == node for d in flood)  # unannounced
    queries = [d for d in flood if d["abbrev"] == "HistoricDataQuery" and d["fields"]["type"] == 1]
    ids = Counter(d["fields"]["req_id"] for d in queries)
    assert max(ids.values()) >= 3 and len(ids) >= 100  # one id reused, and many at once each with its own

