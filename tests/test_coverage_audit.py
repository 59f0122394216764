"""What the behaviour-coverage table calls checked is asserted: the scenario lint refuses a step that claims to cover
(``covers``) a statement it does not assert at its level (a weaker step, a step that lets silence pass, a reply the
seeds let go unanswered), and generate refuses an audit the table disagrees with."""

from __future__ import annotations

import json

import pytest

from imc_conformance.kinds.scenario.coverage import audit_problem, coverage_markdown, statuses


def _case(cases, case_id):
    return json.loads(json.dumps(next(c.data for c in cases if c.id == case_id)))


def test_a_should_step_cannot_check_a_must_statement(suite, cases):
    case = _case(cases, "imc/AcousticOperation/scenario/unsupported-op")
    case["steps"][1]["covers"] = ["AcousticOperation.unsupported"]
    problem = suite.live_problem("scenario", case)
    assert problem[0] == ".steps[1].covers[0]" and "MUST statement" in problem[1] and "SHOULD" in problem[1]
    case["steps"][1]["level"] = "MUST"
    assert suite.live_problem("scenario", case) is None


def test_a_step_that_lets_silence_pass_cannot_check(suite, cases):
    case = _case(cases, "imc/Announce/scenario/well-formed")
    case["steps"][0]["covers"] = ["Announce.sys-name"]
    problem = suite.live_problem("scenario", case)
    assert problem[0] == ".steps[0].covers[0]" and "announce-period" in problem[1]


def test_a_reply_the_seeds_let_go_unanswered_cannot_check(suite, cases):
    for case_id, reading in (("imc/AcousticOperation/scenario/reverse-range", "reverse-range-reply"),
                             ("imc/AcousticOperation/scenario/abort-unreachable", "unknown-system-reply")):
        case = _case(cases, case_id)
        case["steps"][1]["covers"] = ["AcousticOperation.abort"]
        problem = suite.live_problem("scenario", case)
        assert problem[0] == ".steps[1].covers" and reading in problem[1], case_id
    case = _case(cases, "imc/AcousticOperation/scenario/abort")  # to the peer: the seeds define no silence
    assert suite.live_problem("scenario", case) is None and case["steps"][1]["covers"]


def test_every_live_case_passes_the_lint(suite, cases):
    assert [(c.id, suite.live_problem(c.kind, c.data)) for c in cases if c.kind == "scenario"
            and suite.live_problem(c.kind, c.data)] == []


def test_the_audit_agrees_with_the_table_and_is_shown(suite, cases):
    from imc_conformance.suites.imc.paths import imc_data

    document = json.loads(imc_data("statements.json").read_text(encoding="utf-8"))
    live = [c.data for c in cases if c.kind in ("scenario", "robustness")]
    audit = document["audit"]
    assert audit_problem(document["statements"], audit, live) is None
    now = statuses(document["statements"], live)
    assert all(now[m["id"]] == m["to"] for m in audit["moved"])
    text = coverage_markdown("IMC", document["statements"], live, audit=audit)
    assert "## Audit: checked means asserted" in text and all(f"`{m['id']}`" in text for m in audit["moved"])
    first = next(m for m in audit["moved"] if m["to"] == "exercised")
    wrong = dict(audit, moved=[dict(first, to="checked")])
    assert "the table says exercised" in audit_problem(document["statements"], wrong, live)
    claimed = [dict(s, exercised="why") if s["id"] == "LblConfig.get-cfg" else s for s in document["statements"]]
    assert "LblConfig.get-cfg" in audit_problem(claimed, audit, live)


def test_a_damaged_crc_is_sent_as_asked_and_nothing_else_changes(suite, cases):
    """The encoding le-bad-crc (be-bad-crc) sends the frame with every bit of its CRC flipped: invalid by that one
    rule; what a later step reads of it ($sent) is what it says. An encoding the wire does not know is a corpus error."""
    from imc_conformance.kinds.scenario.wire import Addressing
    from imc_conformance.kinds.vector.errors import FrameError
    from imc_conformance.suites.imc import codec

    message = {"abbrev": "HistoricDataQuery", "fields": {"req_id": 7, "type": 1, "max_size": 1000, "data": None}}
    for order in ("le", "be"):
        good = suite.wire.compose(message, order, Addressing(1, 1, 2, 3), 0.0)
        bad = suite.wire.compose(message, f"{order}-bad-crc", Addressing(1, 1, 2, 3), 0.0)
        assert bad.data[:-2] == good.data[:-2] and bytes(a ^ b for a, b in zip(bad.data[-2:], good.data[-2:])) == b"\xff\xff"
        assert bad.decoded == good.decoded
        with pytest.raises(FrameError) as caught:
            codec.decode(suite.defs, bad.data)
        assert "crc" in caught.value.rule
    case = _case(cases, "imc/HistoricDataQuery/scenario/bad-crc-dropped")
    case["steps"][0]["encoding"] = "le-bad"
    problem = suite.live_problem("scenario", case)
    assert problem[0] == ".steps[0].send" and "unknown encoding" in problem[1]


def test_a_silence_filtered_by_fields_counts_only_what_matches(suite, cases):
    """unsupported-op-no-other-state: the reference node's UNSUPPORTED does not break the silence (it is what the
    statement asks), a MSG_FAILURE for the same operation does (break unsupported-as-failure)."""
    from live_harness import run_virtual

    case_id = "imc/AcousticOperation/scenario/unsupported-op-no-other-state"
    chosen = [c for c in cases if c.id == case_id]
    result, _ = run_virtual(suite, chosen)
    case = next(c for c in result.cases if c.id == case_id)
    assert case.verdict.value == "PASS"
    assert any("not what the silence is about" in (e.get("note") or "") for e in case.timeline)
    result, _ = run_virtual(suite, chosen, broken="unsupported-as-failure")
    assert next(c for c in result.cases if c.id == case_id).verdict.value == "FAIL"
