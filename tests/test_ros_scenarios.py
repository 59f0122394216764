"""The same scenario engine for ros_acomms' service contracts: a dynamic queue's GetNextQueuedMessage handler, the
UpdateQueuedMessage events, a modem driver's QueueTxPacket and PingModem. The reference handler passes every
scenario, through a library adapter and through a subprocess adapter; each broken handler is caught."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from imc_conformance.core.runner import run_cases
from imc_conformance.core.verdicts import Verdict
from imc_conformance.sessions.calls import CallTarget
from imc_conformance.sessions.library import LibrarySession
from imc_conformance.sessions.subprocess import SubprocessSession
from imc_conformance.suites.ros_acomms.handler import BREAKS, ReferenceHandler

HERE = Path(__file__).resolve().parent
OPTIONS = {"params": {"ping_dest": 2, "silent_dest": 127}, "effects": {"all"}}
Q = "ros_acomms/GetNextQueuedMessageRequest/scenario/"
CAUGHT = {  # broken handler -> (the case that catches it, its verdict)
    "oversize": (Q + "max-size", "FAIL"),
    "equal-size": (Q + "max-size-equal", "NON_STRICT"),
    "ignores-priority": (Q + "minimum-priority", "FAIL"),
    "ignores-exclude-ids": (Q + "exclude-message-ids", "FAIL"),
    "ignores-require-tags": (Q + "require-tags", "NON_STRICT"),
    "ignores-exclude-tags": (Q + "exclude-tags", "NON_STRICT"),
    "garbage-when-empty": (Q + "empty-queue", "NON_STRICT"),
    "claims-empty": (Q + "returns-the-message", "FAIL"),
    "bits-over-data": (Q + "returns-the-message", "FAIL"),
    "byte-rounded-size": (Q + "returns-the-message", "NON_STRICT"),
    "same-message-id": (Q + "exclude-message-ids", "FAIL"),
    "refuses-dequeued": ("ros_acomms/UpdateQueuedMessage/scenario/every-event-accepted", "FAIL"),
    "tail-position": ("ros_acomms/QueueTxPacketRequest/scenario/insert-at-head", "NON_STRICT"),
    "ping-never-answers": ("ros_acomms/PingModemRequest/scenario/reply", "FAIL"),
    "ping-negative-travel": ("ros_acomms/PingModemRequest/scenario/reply", "FAIL"),
    "wrong-response-type": (Q + "empty-queue", "ADAPTER_ERROR"),
}


@pytest.fixture(scope="module")
def scenarios(ros):
    suite, cases = ros
    return suite, [c for c in cases if c.kind == "scenario"]


def run(suite, cases, session, options=OPTIONS, strict=False):
    return run_cases(CallTarget(session), suite, cases, edition="seed", adapter="handler", options=options,
                     strict=strict, started="2026-01-01T00:00:00+00:00")


def library(broken=None):
    return LibrarySession(ReferenceHandler(broken), "reference-handler")


def verdicts(result) -> dict[str, str]:
    return {c.id: c.verdict.value for c in result.cases}


def test_the_reference_handler_passes_every_scenario(scenarios):
    suite, cases = scenarios
    result = run(suite, cases, library())
    assert len(cases) >= 14 and {c.id for c in cases} <= set(verdicts(result))
    assert {c.id: c.detail for c in result.cases if c.verdict is not Verdict.PASS} == {}
    assert result.exit_code() == 0


def test_the_same_through_a_subprocess_adapter(scenarios):
    suite, cases = scenarios
    session = SubprocessSession([sys.executable, str(HERE / "ros_handler_program.py")], name="handler",
                                encoding_param=suite.encoding_param, cwd=HERE)
    try:
        result = run(suite, cases, session)
    finally:
        session.close()
    assert verdicts(result) == verdicts(run(suite, cases, library())) and result.exit_code() == 0


def test_every_broken_handler_has_a_catching_scenario():
    assert set(CAUGHT) == set(BREAKS) and len(BREAKS) >= 8


@pytest.mark.parametrize("broken", sorted(BREAKS))
def test_each_broken_handler_is_caught(scenarios, broken):
    suite, cases = scenarios
    case_id, verdict = CAUGHT[broken]
    result = run(suite, cases, library(broken))
    found = {c.id: c for c in result.cases}
    assert found[case_id].verdict.value == verdict, found[case_id].detail
    group = case_id.split("/")[1]
    assert found[case_id] in next(m for m in result.messages if m.name == group).cases
    if verdict == "NON_STRICT":
        assert result.exit_code() == 0 and run(suite, cases, library(broken), strict=True).exit_code() == 1
    else:
        assert result.exit_code() == (2 if verdict == "ADAPTER_ERROR" else 1)


def test_a_wrong_response_type_names_the_step(scenarios):
    suite, cases = scenarios
    result = run(suite, cases, library("wrong-response-type"))
    case = next(c for c in result.cases if c.id == Q + "empty-queue")
    assert "step ask: malformed response" in case.detail and "QueueTxPacketResponse" in case.detail


def test_missing_parameters_and_effects_are_reported(scenarios):
    suite, cases = scenarios
    result = run(suite, cases, library(), options={"params": {}, "effects": set()})
    assert "ros_acomms/PingModemRequest/scenario/reply" not in verdicts(result)  # effects not allowed
    assert any("effects not allowed: transmits-acoustically" in n for n in result.notes)
    result = run(suite, cases, library(), options={"params": {}, "effects": {"all"}})
    case = next(c for c in result.cases if c.id == "ros_acomms/PingModemRequest/scenario/reply")
    assert case.verdict is Verdict.INCONCLUSIVE and "--param ping_dest=" in case.detail


def test_a_handler_without_a_service_is_unsupported(scenarios):
    suite, cases = scenarios

    class QueueOnly(ReferenceHandler):
        def setup(self, suite, service, state):
            if service != "GetNextQueuedMessage":
                from imc_conformance.adapter_api import Unsupported
                raise Unsupported(f"no {service}")
            super().setup(suite, service, state)

    result = run(suite, cases, LibrarySession(QueueOnly(), "queue-only"))
    found = verdicts(result)
    assert found["ros_acomms/QueueTxPacketRequest/scenario/queued"] == "UNSUPPORTED"
    assert found[Q + "max-size"] == "PASS" and result.exit_code() == 0


def test_a_codec_adapter_runs_no_scenario(ros, rosbags_adapter):
    suite, cases = ros
    result = run(suite, [c for c in cases if c.group == "UpdateQueuedMessage"], LibrarySession(rosbags_adapter, "rosbags"))
    assert all("/scenario/" not in c.id for c in result.cases)
    assert any("cases not run (1 scenario)" in n for n in result.notes)


def test_every_testable_ros_statement_is_covered(scenarios):
    from imc_conformance.kinds.scenario.coverage import coverers

    suite, cases = scenarios
    covered = coverers([c.data for c in cases]) | coverers([c.data for c in cases], "exercises")
    assert [s["id"] for s in suite.statements if "untestable" not in s and s["id"] not in covered] == []
