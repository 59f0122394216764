"""Behaviour the seeds allow, which the suite used to fail: a node that queues acoustic operations answers the
robustness probe once its queue drains (the probe's wait grows with the requests of its kind just replayed, by the
register's bound ``acoustic-queue``); an Iridium status that reaches the suite shortly after the ttl (the register's
bound ``link``). Each shown by a variant of the reference node, in both editions, on virtual time."""

from __future__ import annotations

import copy

import pytest

from imc_conformance.core.verdicts import Verdict
from imc_conformance.kinds.robustness.phase import PhaseMachine

from live_harness import recorded_run, run_virtual

PROBE = "imc/AcousticOperation/robustness/still-served"


def unexpected(result) -> dict[str, str]:
    return {c.id: c.detail for c in result.cases if c.verdict not in (Verdict.PASS, Verdict.IMPL_DEFINED)}


@pytest.mark.parametrize("edition", ["imc-5.4.30", "imc-5.4.11"])
def test_a_node_that_queues_acoustic_operations_still_serves_the_probe(suite, cases, edition):
    result, _ = run_virtual(suite, cases, edition, kinds=("scenario", "robustness"), variant="queues-operations",
                            strict=True)
    assert unexpected(result) == {} and result.exit_code() == 0
    case = next(c for c in result.cases if c.id == PROBE)
    assert case.verdict is Verdict.PASS
    assert any("probe:corpus" == k.check and k.verdict is Verdict.PASS for k in case.checks)


def test_without_the_queue_bound_the_same_node_would_be_taken_for_silenced(suite, cases, monkeypatch):
    monkeypatch.setattr(PhaseMachine, "_queue", lambda self, spec, frames: 0)
    result, _ = run_virtual(suite, cases, kinds=("robustness",), variant="queues-operations")
    case = next(c for c in result.cases if c.id == PROBE)
    assert case.verdict is Verdict.FAIL and "no AcousticOperation after block" in case.detail


def test_a_probe_silenced_for_good_is_still_caught_and_names_its_longer_wait(suite, cases):
    """A node whose acoustic requests stop being served after the corpus: the probe waits out its queue bound once,
    then fails, its timeline naming the wait and the requests it counted."""
    result, _ = run_virtual(suite, cases, kinds=("robustness",), broken="dies-on-own-id")
    case = next(c for c in result.cases if c.id == PROBE)
    notes = [e["note"] for e in case.timeline if e.get("event") == "probe" and "no AcousticOperation" in e["note"]]
    assert case.verdict is Verdict.FAIL and "hostile block from-own-id" in case.detail
    assert any("bound acoustic-queue" in n and "for each of the 1 request of its kind" in n for n in notes), notes


def test_the_ttl_tolerance_is_the_registers_and_a_default_is_refused(suite, cases):
    case = copy.deepcopy(next(c.data for c in cases if c.id == "imc/IridiumMsgTx/scenario/ttl"))
    step = case["steps"][1]
    assert step["not_after"]["tolerance"] == "link" and suite.behaviour["bounds"]["link"]["seconds"] >= 2.5
    del step["not_after"]["tolerance"]
    problem = suite.live_problem("scenario", case)
    assert problem[0] == ".steps[1].not_after.tolerance" and "names its source" in problem[1]


@pytest.mark.parametrize("variant", ["reused-id-replaces", "reused-id-cancels"])
def test_a_reused_request_id_replacing_or_cancelling_is_a_reading_live_and_in_its_recording(suite, cases, tmp_path,
                                                                                             variant):
    """One chain or two: a node whose second request with the same req_id replaces the first (the first says nothing
    more) or cancels it (the first ends in ERROR, the second is not carried out) fails nothing, live or judged again
    from its recording by the passive exchange rules; each shows the reading reused-request-id."""
    import json

    from imc_conformance.cli import main

    path, out = tmp_path / "run.pcapng", tmp_path / "judged.json"
    live = recorded_run(suite, cases, path, variant=variant)
    case = next(c for c in live.cases if c.id == "imc/AcousticRequest/scenario/reused-id")
    assert case.verdict is Verdict.IMPL_DEFINED and any(k.check.endswith(":reading-reused-request-id") for k in case.checks)
    assert main(["pcap", str(path), "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    judged = {c["id"]: c["verdict"] for m in doc["messages"] for c in m["cases"]}
    assert judged["imc/AcousticRequest/capture/exchange/acoustic-request/reading/reused-request-id"] == "IMPL_DEFINED"
    assert not {k: v for k, v in judged.items() if v not in ("PASS", "IMPL_DEFINED")}


def test_a_probes_queue_bound_is_one_of_the_registers(suite, cases):
    case = copy.deepcopy(next(c.data for c in cases if c.id == PROBE))
    assert case["probe"]["queued"] == "acoustic-queue" and suite.live_problem("robustness", case) is None
    case["probe"]["queued"] = "a-while"
    problem = suite.live_problem("robustness", case)
    assert problem[0].endswith(".queued") and "names its source" in problem[1]


def test_a_state_outside_a_table_stays_a_reading_though_its_entry_is_a_should(suite, cases):
    """Only a request's silence takes its register entry's SHOULD: an Iridium status outside IridiumTxStatus's table
    (entry states-without-a-table, whose SHOULD is the rules of one terminal state) is still an IMPL_DEFINED reading (the
    scenario's own terminal rule judges the value apart)."""
    from imc_conformance.suites.imc.node import ReferenceNode

    class OddStatus(ReferenceNode):
        def _reply(self, t, delay, request, abbrev, fields, entity=0, tag=None):
            if abbrev == "IridiumTxStatus" and fields["status"] == self._v("IridiumTxStatus", "status", "OK"):
                fields = dict(fields, status=77)  # a status the table does not name
            super()._reply(t, delay, request, abbrev, fields, entity, tag)

    from live_harness import NODE, virtual_session, EVERYTHING
    from imc_conformance.core.runner import run_cases

    node = OddStatus(suite.defs, suite.behaviour, edition=suite.editions[0], address=NODE)
    session, link = virtual_session(suite, suite.editions[0], node=node)
    chosen = [c for c in cases if c.id == "imc/IridiumMsgTx/scenario/status"]
    result = run_cases(session, suite, chosen, edition=suite.editions[0], adapter="virtual", options=EVERYTHING,
                       clock=link.now)
    case = result.cases[0]
    assert suite.behaviour["ambiguities"]["states-without-a-table"]["level"] == "SHOULD"
    assert any(k.check.endswith(":reading-states-without-a-table") and k.verdict is Verdict.IMPL_DEFINED
               for k in case.checks)


def test_no_report_for_a_disbanded_group_is_a_reading_live_and_in_its_recording(suite, cases, tmp_path):
    """A node that leaves a SystemGroup Req for a group it no longer holds unanswered fails nothing, live or judged
    again from its recording by the passive exchange rules (the Dis before it, from the same requester, selects the
    request); each shows the reading disbanded-group-request."""
    import json

    from imc_conformance.cli import main

    chosen = [c for c in cases if c.id == "imc/SystemGroup/scenario/disband-then-request"]
    path, out = tmp_path / "run.pcapng", tmp_path / "judged.json"
    live = recorded_run(suite, chosen, path, variant="silent-on-unknown-group")
    case = next(c for c in live.cases if c.id == chosen[0].id)
    assert case.verdict is Verdict.IMPL_DEFINED
    assert any(k.check.endswith(":reading-disbanded-group-request") for k in case.checks)
    assert main(["pcap", str(path), "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    judged = {c["id"]: c["verdict"] for m in doc["messages"] for c in m["cases"]}
    assert judged["imc/SystemGroup/capture/exchange/system-group/reading/disbanded-group-request"] == "IMPL_DEFINED"
    assert not {k: v for k, v in judged.items() if v not in ("PASS", "IMPL_DEFINED")}
