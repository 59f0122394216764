"""The scenario engine against the reference node and every broken node, on virtual time (no test here depends
on wall-clock speed): the reference passes every scenario, each broken behaviour is caught by the scenario that
checks its rule, with the right message named, and loss and duplication are absorbed deterministically."""

from __future__ import annotations

import json
import re

import pytest

from imc_conformance.core.verdicts import Verdict
from imc_conformance.kinds.scenario.options import claims
from imc_conformance.render import RENDERERS
from imc_conformance.suites.imc.node import BREAKS, VARIANTS
from live_harness import EVERYTHING, PARAMS, run_virtual, scenario_cases

# broken behaviour -> (a case that must catch it, its verdict): the case names the message the rule belongs to
CAUGHT = {
    "req-id-not-echoed": ("imc/AcousticRequest/scenario/range", "FAIL"),
    "type-not-echoed": ("imc/AcousticRequest/scenario/range", "FAIL"),
    "seq-not-echoed": ("imc/SmsTx/scenario/state", "FAIL"),
    "wrong-system": ("imc/AcousticOperation/scenario/range", "FAIL"),
    "status-after-terminal": ("imc/AcousticRequest/scenario/msg", "NON_STRICT"),
    "two-terminals": ("imc/AcousticRequest/scenario/msg", "NON_STRICT"),
    "no-terminal": ("imc/AcousticRequest/scenario/range", "NON_STRICT"),
    "wrong-kind-terminal": ("imc/AcousticOperation/scenario/range", "FAIL"),
    "no-cur-cfg": ("imc/LblConfig/scenario/get-cfg", "FAIL"),
    "other-beacons": ("imc/LblConfig/scenario/set-then-get", "FAIL"),
    "ignores-big-endian": ("imc/AcousticSystemsQuery/scenario/reply-big-endian", "FAIL"),
    "big-endian-le-crc": ("imc/AcousticStatus/passive/AcousticRequest/scenario/range", "FAIL"),
    "late": ("imc/AcousticSystemsQuery/scenario/reply", "FAIL"),
    "dies-after-raw": ("imc/AcousticRequest/scenario/msg-without-message", "FAIL"),
    "malformed-reply": ("imc/AcousticSystems/passive/AcousticSystemsQuery/scenario/reply", "FAIL"),
    "broadcast-replies": ("imc/AcousticRequest/scenario/range", "FAIL"),
    "from-other-system": ("imc/AcousticSystemsQuery/scenario/reply", "FAIL"),
    "raw-accepted": ("imc/AcousticRequest/scenario/raw-without-devdatabinary", "NON_STRICT"),
    "keeps-expired-commands": ("imc/RemoteCommand/scenario/expired-dropped", "FAIL"),
    "no-heartbeat": ("imc/Heartbeat/scenario/periodic", "NON_STRICT"),
    "silent-on-unsupported": ("imc/AcousticOperation/scenario/unsupported-op", "NON_STRICT"),
    "ignores-timeout": ("imc/AcousticRequest/scenario/timeout", "NON_STRICT"),
    "ignores-max-size": ("imc/HistoricDataQuery/scenario/max-size", "NON_STRICT"),
    "transmits-logged-samples": ("imc/HistoricDataQuery/scenario/sample-priority", "FAIL"),
    "transmits-in-arrival-order": ("imc/HistoricDataQuery/scenario/sample-order", "FAIL"),
    "merges-set-cfg": ("imc/LblConfig/scenario/set-replaces", "FAIL"),
    "stores-cur-cfg": ("imc/LblConfig/scenario/cur-cfg-is-a-reply", "NON_STRICT"),
    "stops-after-unknown-op": ("imc/LblConfig/scenario/unknown-op", "FAIL"),
    "acks-unreachable": ("imc/AcousticOperation/scenario/abort-unreachable", "FAIL"),
    "resends-expired": ("imc/RemoteCommand/scenario/expires-while-stored", "FAIL"),
    "transmits-after-ttl": ("imc/IridiumMsgTx/scenario/ttl", "FAIL"),
    "replies-to-first-client": ("imc/AcousticSystemsQuery/scenario/two-clients", "FAIL"),
    "never-forwards": ("imc/RemoteCommand/scenario/forwarded-to-recipient", "NON_STRICT"),
    "ignores-remote-commands": ("imc/RemoteCommand/scenario/executed", "NON_STRICT"),
    "acknowledges-set-cfg": ("imc/LblConfig/scenario/set-then-get", "NON_STRICT"),
    "leaks-on-drop": ("imc/AcousticSystemsQuery/robustness/still-served", "FAIL"),
    "list-empty-items": ("imc/AcousticSystemsQuery/scenario/reply", "NON_STRICT"),
    "two-replies": ("imc/AcousticSystemsQuery/scenario/reply", "NON_STRICT"),
    "ignores-anyone": ("imc/AcousticSystemsQuery/scenario/to-anyone", "NON_STRICT"),
    "acts-on-others-requests": ("imc/LblConfig/scenario/set-for-another-system", "NON_STRICT"),
    "trusts-own-id": ("imc/LblConfig/scenario/spoofed-own-source", "NON_STRICT"),
    "rounds-beacons": ("imc/LblConfig/scenario/set-then-get", "NON_STRICT"),
    "drops-when-many": ("imc/HistoricDataQuery/scenario/many-at-once", "FAIL"),
    "rewrites-producer": ("imc/HistoricDataQuery/scenario/keeps-producer", "NON_STRICT"),
    "executes-others-commands": ("imc/RemoteCommand/scenario/not-executed-for-another", "NON_STRICT"),
    "late-ok": ("imc/IridiumMsgTx/scenario/ttl", "FAIL"),
    "no-group-report": ("imc/SystemGroup/scenario/set-then-request", "NON_STRICT"),
    "forwards-as-own": ("imc/RemoteCommand/scenario/forwarded-to-recipient", "NON_STRICT"),
    "unknown-system-type": ("imc/Announce/scenario/well-formed", "NON_STRICT"),
    "replies-to-every-client": ("imc/AcousticSystemsQuery/scenario/two-clients", "NON_STRICT"),
    "dies-on-own-id": ("imc/AcousticRequest/robustness/still-served", "FAIL"),
    "exhausted-by-many": ("imc/HistoricDataQuery/robustness/still-served", "FAIL"),
    "reused-id-crossed": ("imc/AcousticRequest/scenario/reused-id", "NON_STRICT"),
    "dies-on-reused-id": ("imc/AcousticRequest/scenario/reused-id", "FAIL"),
    "silent-on-abort": ("imc/AcousticOperation/scenario/abort", "FAIL"),
    "msg-ends-in-range": ("imc/AcousticOperation/scenario/msg", "FAIL"),
    "answers-bad-crc": ("imc/HistoricDataQuery/scenario/bad-crc-dropped", "FAIL"),
    "forwards-expired": ("imc/RemoteCommand/scenario/expired-not-forwarded", "FAIL"),
    "forwards-expired-stored": ("imc/RemoteCommand/scenario/expires-before-recipient-appears", "FAIL"),
    "dies-on-empty-msg": ("imc/AcousticOperation/scenario/msg-without-message-then-served", "FAIL"),
    "transmits-newest-first": ("imc/HistoricDataQuery/scenario/sample-order-rounds", "FAIL"),
    "late-success": ("imc/IridiumMsgTx/scenario/gateway-slow-then-back", "FAIL"),
    "no-lbl-ranges": ("imc/LblConfig/scenario/ranges-after-set", "NON_STRICT"),
    "restarts-on-empty-msg": ("imc/AcousticOperation/scenario/range-outlives-msg-without-message", "FAIL"),
    "empty-when-small": ("imc/HistoricDataQuery/scenario/sample-order", "NON_STRICT"),
    "clear-keeps-data": ("imc/HistoricDataQuery/scenario/clear-empties", "NON_STRICT"),
    "ok-when-gateway-fails": ("imc/IridiumMsgTx/scenario/gateway-fails", "NON_STRICT"),
    "error-without-text": ("imc/IridiumMsgTx/scenario/gateway-gone", "NON_STRICT"),
    "retries-after-ttl": ("imc/IridiumMsgTx/scenario/gateway-slow", "FAIL"),
    "sms-ignores-timeout": ("imc/SmsTx/scenario/gateway-slow", "NON_STRICT"),
    "answers-replies": ("imc/HistoricDataQuery/scenario/not-a-query", "NON_STRICT"),
    "answers-unsolicited-systems": ("imc/AcousticSystemsQuery/scenario/unsolicited-systems", "NON_STRICT"),
    "unsupported-as-failure": ("imc/AcousticOperation/scenario/unsupported-op-no-other-state", "FAIL"),
    "succeeds-to-unknown": ("imc/AcousticRequest/scenario/unknown-destination-never-succeeds", "NON_STRICT"),
    "dies-on-compressed-history": ("imc/HistoricDataQuery/scenario/compressed-history", "FAIL"),
    "repeat-range-drops-both": ("imc/AcousticOperation/scenario/two-ranges-one-system", "FAIL"),
    "lists-other-names": ("imc/AcousticOperation/scenario/range-listed-system", "NON_STRICT"),
    "beats-only-when-answered": ("imc/Heartbeat/scenario/heartbeat-answered", "NON_STRICT"),
    "keeps-disbanded-group": ("imc/SystemGroup/scenario/disband-then-request", "NON_STRICT"),
}


READINGS = {  # variant -> the open readings (ambiguities.json) it takes, each shown as an IMPL_DEFINED check
    "sent-before-range-received": {"sent-in-a-range"},
    "busy-then-completes": {"busy-ends-request"},
    "queued-first": set(),
    "silent-where-allowed": {"reverse-range-reply", "msg-short-reply", "msg-without-message",
                             "request-reverse-range-reply"},
    "old-unsupported-code": {"status-outside-the-table"},
    "slow-announce": {"announce-period"},
    "msg-to-unreachable-done": set(),
    "silent-to-unknown-systems": {"unknown-system-reply"},
    "declines-reverse-range": set(),  # declining is shown as UNSUPPORTED, not as a reading
    "answers-queries-for-others": set(),  # it answers where the reference node leaves the query (addressed-elsewhere)
    "trusts-unannounced": {"unannounced-sender"},
    "vehicle-traffic": set(),  # its other traffic is counted in a note, judged no further
    "queues-operations": set(),  # its queue shows in the robustness phase (tests/test_allowed_readings.py)
    "slow-iridium-link": set(),  # its late OK is within the register's bound "link"
    "reused-id-replaces": {"reused-request-id"},  # the first, replaced, says nothing more
    "reused-id-cancels": {"reused-request-id"},  # the second, cancelling the first, is not carried out
    "repeat-range-replaces": {"two-requests-one-system"},  # one terminal for two RANGEs to one system
    "loses-first-copy": set(),  # every idempotent request answered on its resend
    "forwards-on-period": set(),  # kept commands forwarded every 30 s, as DUNE, never an expired one
    "answers-heartbeats": {"heartbeat-reply"},  # its answer, addressed to the session, recorded
    "silent-on-unknown-group": {"disbanded-group-request"},  # its silence for a disbanded group, recorded
    # the copy's reply not given, recorded; two RANGEs to one system sent together are byte for byte the same, so it
    # takes the second for the link's copy: one terminal state for the two
    "answers-a-copy-once": {"duplicated-request", "two-requests-one-system"},
}


# variant -> the readings it takes whose register entry is a SHOULD: silence where the seeds define a reply without
# requiring it, each a NON_STRICT check (failing only under --strict), never a FAIL
SILENT_WHERE_A_REPLY_IS_DEFINED = {
    "silent-where-allowed": {"msg-short-reply", "msg-without-message", "reverse-range-reply",
                             "request-reverse-range-reply"},
    "silent-to-unknown-systems": {"unknown-system-reply"},
}


def verdicts(result) -> dict[str, str]:
    return {c.id: c.verdict.value for c in result.cases}


@pytest.mark.parametrize("edition", ["imc-5.4.30", "imc-5.4.11"])
def test_the_reference_node_passes_every_scenario(suite, cases, edition):
    result, _ = run_virtual(suite, cases, edition)
    scenarios = [c for c in result.cases if "/passive/" not in c.id]
    assert len(scenarios) == len(scenario_cases(cases)) >= 30
    assert {c.id: c.detail for c in result.cases if c.verdict not in (Verdict.PASS, Verdict.IMPL_DEFINED)} == {}
    readings = [k for c in result.cases for k in c.checks if k.verdict is Verdict.IMPL_DEFINED]
    assert readings and all(":reading-" in k.check and "open reading" in k.detail for k in readings)
    assert result.exit_code() == 0
    passive = [c for c in result.cases if "/passive/" in c.id]
    assert passive and all(c.checks for c in passive)  # every frame a scenario looked at was judged by the bytes


def test_every_broken_behaviour_has_a_catching_scenario():
    assert set(CAUGHT) == set(BREAKS) and len(BREAKS) >= 14


@pytest.mark.parametrize("broken", sorted(BREAKS))
def test_each_broken_node_is_caught(suite, cases, broken):
    case_id, verdict = CAUGHT[broken]
    kinds = ("robustness",) if "/robustness/" in case_id else ("scenario",)
    result, _ = run_virtual(suite, cases, broken=broken, kinds=kinds)
    assert verdicts(result).get(case_id) == verdict, next((c.detail for c in result.cases if c.id == case_id), "absent")
    case = next(c for c in result.cases if c.id == case_id)
    group = case_id.split("/")[1]
    message = next(m for m in result.messages if m.name == group)
    assert case in message.cases  # filed under the message the rule belongs to
    if verdict == "FAIL":
        assert result.exit_code() == 1 and message.verdict == "FAIL"
    else:  # a SHOULD: caught, failing only under --strict
        assert result.exit_code() == 0
        strict, _ = run_virtual(suite, cases, broken=broken, strict=True, kinds=kinds)
        assert strict.exit_code() == 1


def test_a_failing_scenario_keeps_its_timeline(suite, cases):
    result, _ = run_virtual(suite, cases, broken="two-terminals")
    case = next(c for c in result.cases if c.id == "imc/AcousticRequest/scenario/msg")
    events = [(e["event"], e.get("note", "")) for e in case.timeline]
    assert events[0][0] == "sent" and case.timeline[0]["bytes"].startswith("54fe")
    assert any("after the terminal state" in note for _, note in events)
    failed = [k for k in case.checks if k.verdict is Verdict.NON_STRICT]  # DUNE's practice, not the seed's words
    assert [k.check for k in failed] == ["step:status:after-terminal"] and failed[0].clause
    for fmt, render in RENDERERS.items():
        text = render(result)
        assert "after the terminal state" in text or fmt == "json" and "after-terminal" in text


def test_the_html_report_shows_every_scenarios_timeline_and_the_bound_that_decided_each_step(suite, cases):
    from imc_conformance.render.html import render_html
    from imc_conformance.schemas import schema_error
    from imc_conformance.paths import VECTORS

    chosen = [c for c in cases if c.group in ("LblConfig", "AcousticSystemsQuery")]
    result, _ = run_virtual(suite, chosen, broken="no-cur-cfg")
    case = next(c for c in result.cases if c.id == "imc/LblConfig/scenario/get-cfg")
    timer = next(e for e in case.timeline if e["event"] == "timer")
    assert timer["bound"] == {"of": "within", "seconds": 5.0, "name": "first-reply"}
    assert timer["note"] == "the step's time is up: its within bound, 5 s (first-reply), ran out, after 5 tries"
    assert schema_error(VECTORS / "schema" / "result.schema.json", result.to_dict(), "result") is None
    html = render_html(result)
    failed = html.split(f'data-case="{case.id}"', 1)[1].split("</section>", 1)[0]
    decided = re.findall(r'<tr data-event="(\w+)" class="decided">', failed)
    assert decided == ["timer"] and "its within bound, 5 s (first-reply), ran out, after 5 tries" in failed
    others = [c for c in result.cases if c.timeline and c.verdict is Verdict.PASS]
    assert others and all(f'<details class="scenario" data-case="{c.id}"' in html for c in others)
    replied = html.split(f'<details class="scenario" data-case="{others[0].id}"', 1)[1].split("</details>\n", 1)[0]
    assert 'class="decided"' in replied


CRASH_AT = 30.0  # virtual seconds into the run


def crashing_node(suite, **options):
    """The reference node until CRASH_AT, then a crashed process: nothing comes in or goes out."""
    from imc_conformance.suites.imc.node import ReferenceNode
    from live_harness import NODE

    class CrashingNode(ReferenceNode):
        def receive(self, t, data, source):
            if t < CRASH_AT:
                super().receive(t, data, source)

        def due(self, t):
            return super().due(t) if t < CRASH_AT else []

        @property
        def deadline(self):
            deadline = super().deadline
            return deadline if deadline is not None and deadline < CRASH_AT else None

    return CrashingNode(suite.defs, suite.behaviour, edition=suite.editions[0], address=NODE, **options)


@pytest.mark.parametrize("beats", [True, False])
def test_a_node_that_stops_sending_anything_is_taken_for_gone_and_what_waits_on_it_is_decided_then(suite, cases,
                                                                                                     beats):
    """Liveness: a node that heart-beat and then sends nothing at all is taken for gone once, and every step still
    waiting on it is decided then, untested (INCONCLUSIVE, never FAIL), instead of each waiting out its bound; a node
    that never heart-beats is never taken for gone (its silent steps wait their bounds, and fail)."""
    from imc_conformance.core.runner import run_cases
    from live_harness import virtual_session

    node = crashing_node(suite, **({} if beats else {"broken": "no-heartbeat"}))
    session, link = virtual_session(suite, suite.editions[0], node=node)
    result = run_cases(session, suite, scenario_cases(cases), edition=suite.editions[0], adapter="virtual", options=EVERYTHING,
                       clock=link.now)
    after = [c for c in result.cases if c.timeline and any(e["event"] == "gone" for e in c.timeline)]
    if not beats:
        assert not result.incidents and not after and any(c.verdict is Verdict.FAIL for c in result.cases)
        return
    [gone] = result.incidents
    assert gone.kind == "gone" and "taken for gone" in gone.reason and sorted(gone.cases) == sorted(c.id for c in after)
    assert result.exit_code() == 1  # a node that stops mid-run fails the run, though no step could be judged
    from imc_conformance.paths import VECTORS
    from imc_conformance.schemas import schema_error

    assert schema_error(VECTORS / "schema" / "result.schema.json", result.to_dict(), "result") is None
    for fmt, render in RENDERERS.items():
        assert "decided then, untested" in render(result), fmt
    for case in after:
        assert case.verdict in (Verdict.INCONCLUSIVE, Verdict.PASS, Verdict.IMPL_DEFINED), (case.id, case.detail)
        decided = [e for e in case.timeline if e["event"] == "gone"]
        assert all(e["note"].startswith("decided before its") for e in decided)
    assert any(c.verdict is Verdict.INCONCLUSIVE for c in after)
    assert not [c.id for c in result.cases if c.verdict in (Verdict.FAIL, Verdict.NON_STRICT)]
    assert link.now() < CRASH_AT + 10  # decided once it was gone, not bound after bound (261 s without liveness)


@pytest.mark.parametrize("seed", range(1, 21))
def test_loss_and_duplication_are_absorbed_and_reruns_are_identical(suite, cases, seed):
    first, _ = run_virtual(suite, cases, loss=0.1, dup=0.05, seed=seed)
    assert {c.id: c.detail for c in first.cases if c.verdict not in (Verdict.PASS, Verdict.IMPL_DEFINED)} == {}
    again, _ = run_virtual(suite, cases, loss=0.1, dup=0.05, seed=seed)
    assert json.dumps(first.to_dict(), sort_keys=True) == json.dumps(again.to_dict(), sort_keys=True)


def test_resends_and_duplicates_are_reported(suite, cases):
    notes = []
    for seed in range(1, 21):
        result, _ = run_virtual(suite, cases, loss=0.1, dup=0.05, seed=seed)
        notes += [k.detail for c in result.cases for k in c.checks] + [e.get("note", "") for c in result.cases for e in c.timeline]
    assert any("answered on try 2" in n for n in notes)
    assert any("byte-identical copy" in n for n in notes)


def test_a_missing_parameter_is_inconclusive_and_names_it(suite, cases):
    result, _ = run_virtual(suite, cases, options={"params": {}, "effects": {"all"}})
    case = next(c for c in result.cases if c.id == "imc/AcousticRequest/scenario/range")
    assert case.verdict is Verdict.INCONCLUSIVE and "--param peer=" in case.detail
    assert result.exit_code() == 0  # other scenarios were tested and pass
    strict, _ = run_virtual(suite, cases, options={"params": {}, "effects": {"all"}}, strict=True)
    assert strict.exit_code() == 1  # --strict makes INCONCLUSIVE failing


def test_effects_are_opt_in_and_the_report_says_what_was_skipped(suite, cases):
    result, _ = run_virtual(suite, cases, options={"params": PARAMS})
    ran = {c.id for c in result.cases}
    assert "imc/AcousticRequest/scenario/range" not in ran and "imc/AcousticSystemsQuery/scenario/reply" in ran
    assert any("effects not allowed: transmits-acoustically" in n for n in result.notes)
    some, _ = run_virtual(suite, cases, options={"params": PARAMS, "effects": {"changes-configuration"}})
    assert "imc/LblConfig/scenario/set-then-get" in {c.id for c in some.cases}


def test_unclaimed_capabilities_are_not_claimed_and_claimed_silence_fails(suite, cases):
    options = dict(EVERYTHING, claims=claims(suite.behaviour, {"services": ["discovery", "lbl"]}))
    result, _ = run_virtual(suite, cases, options=options)
    by_id = {c.id: c for c in result.cases}
    sms = by_id["imc/SmsTx/scenario/state"]
    assert sms.verdict is Verdict.UNSUPPORTED and "not claimed: sms" in sms.detail
    assert by_id["imc/LblConfig/scenario/get-cfg"].verdict is Verdict.PASS
    by_message = {m.name: m.verdict for m in result.messages}
    assert by_message["SmsTx"] == "UNSUPPORTED" and by_message["LblConfig"] == "PASS"  # nothing passed for SmsTx
    silent, _ = run_virtual(suite, cases, options=options, broken="no-cur-cfg")
    assert {c.id: c.verdict for c in silent.cases}["imc/LblConfig/scenario/get-cfg"] is Verdict.FAIL


def test_a_capability_served_only_to_the_node_itself_is_not_claimed_for_the_suite(suite, cases):
    """A node that serves AcousticRequest only to its own system (as DUNE does: a local API) fails every
    AcousticRequest scenario unless its claims say so; with them, those cases are not claimed (never PASS, never
    FAIL) and the rest of the acoustic service is judged as usual, even under --strict."""
    kinds = ("scenario", "robustness")
    local = {"only_to_itself": ("acoustic-request",)}
    unclaimed, _ = run_virtual(suite, cases, kinds=kinds, **local)
    request = [c for c in unclaimed.cases if c.id.startswith("imc/AcousticRequest/")]
    assert request and {c.verdict for c in request} >= {Verdict.FAIL}
    doc = {"services": sorted(suite.behaviour["services"]), "capabilities": {"acoustic-request": "self"}}
    result, _ = run_virtual(suite, cases, options=dict(EVERYTHING, claims=claims(suite.behaviour, doc)), strict=True,
                            kinds=kinds, **local)
    request = [c for c in result.cases if c.id.startswith("imc/AcousticRequest/")]
    assert len(request) == len([c for c in cases if c.id.startswith("imc/AcousticRequest/") and c.kind in kinds])
    assert {c.verdict for c in request} == {Verdict.UNSUPPORTED}
    assert all("only to its own system" in c.detail for c in request)
    assert {c.id: c.detail for c in result.cases if c.verdict not in (Verdict.PASS, Verdict.IMPL_DEFINED)
            and not c.id.startswith("imc/AcousticRequest/")} == {}
    assert {m.name: m.verdict for m in result.messages}["AcousticOperation"] in ("PASS", "IMPL_DEFINED")


def test_claims_are_checked_against_the_vocabulary(suite):
    for doc, says in (({"services": ["telepathy"]}, "unknown service 'telepathy'"),
                      ({"capabilities": {"telepathy": "any"}}, "unknown capability 'telepathy'"),
                      ({"capabilities": {"acoustic-request": "sometimes"}}, "is not one of any, self, none"),
                      ({}, 'expected {"services"'), ({"capabilities": ["acoustic-request"]}, 'expected {"services"')):
        with pytest.raises(ValueError, match=re.escape(says)):
            claims(suite.behaviour, doc)
    both = claims(suite.behaviour, {"services": ["acoustic"], "capabilities": {"acoustic-request": "none",
                                                                             "system-group": "self"}})
    assert both == {"acoustic-operation": "any", "acoustic-systems": "any", "system-group": "self"}


def test_a_target_claiming_nothing_the_cases_check_exits_2(suite, cases):
    only_sms = [c for c in cases if c.id.startswith("imc/SmsTx/")]
    result, _ = run_virtual(suite, only_sms, options=dict(EVERYTHING, claims={"lbl-configuration": "any"}))
    assert {c.verdict for c in result.cases} == {Verdict.UNSUPPORTED}
    assert result.exit_code() == 2  # nothing was tested: never a green run


def test_a_silent_target_makes_everything_inconclusive_and_exits_2(suite, cases):
    class Silent:
        deadline = None

        def receive(self, t, data, source):
            pass

        def due(self, t):
            return []

    from live_harness import virtual_session
    from imc_conformance.core.runner import run_cases

    session, link = virtual_session(suite, suite.editions[0], node=Silent())
    result = run_cases(session, suite, scenario_cases(cases), edition=suite.editions[0], adapter="virtual",
                       options=EVERYTHING, clock=link.now)
    assert {c.verdict for c in result.cases} == {Verdict.INCONCLUSIVE}
    assert "no valid frame" in result.cases[0].detail and result.exit_code() == 2
    assert {m.verdict for m in result.messages} == {"INCONCLUSIVE"}


def test_the_session_announces_and_heartbeats_before_expecting_answers(suite, cases):
    _, link = run_virtual(suite, cases)
    first = [suite.wire.parse(d) for d in link.sent[:14]]
    assert first[0].message == "Announce" and "Heartbeat" in [p.message for p in first]
    announced = {p.decoded["header"]["src"]: p.fields["sys_name"] for p in first if p.message == "Announce"}
    assert len(announced) == 2 and len(set(announced.values())) == 2  # the second client, under its own name
    assert sum(suite.wire.parse(d).message == "Heartbeat" for d in link.sent) >= 5  # 1 Hz over the run


def test_the_profile_can_excuse_but_never_pass_silence(suite, cases):
    profile = {"name": "lenient", "rules": [
        {"scenarios": ["imc/LblConfig/scenario/get-cfg"], "relax": ["step:current", "step:current:fields"], "citation": "x"},
        {"scenarios": ["imc/SmsTx/*"], "not_applicable": "no SMS here", "citation": "y"}]}
    result, _ = run_virtual(suite, cases, options=dict(EVERYTHING, profile=profile), broken="no-cur-cfg")
    by_id = {c.id: c for c in result.cases}
    assert by_id["imc/LblConfig/scenario/get-cfg"].verdict is Verdict.FAIL  # the reply itself cannot be relaxed
    assert by_id["imc/SmsTx/scenario/state"].verdict is Verdict.INCONCLUSIVE
    assert "no SMS here (y)" in by_id["imc/SmsTx/scenario/state"].detail


def test_every_testable_statement_is_covered_and_every_live_case_covers_one(suite, cases):
    from imc_conformance.kinds.scenario.coverage import coverers

    live = [c.data for c in cases if c.kind in ("scenario", "robustness")]
    covered = coverers(live) | coverers(live, "exercises")
    testable = [s["id"] for s in suite.statements if "untestable" not in s]
    assert len(suite.statements) >= 70 and [s for s in testable if s not in covered] == []
    assert [c["id"] for c in live if not c.get("covers")
            and not any(s.get("covers") or s.get("exercises") for s in c.get("steps", ()))] == []


def test_what_the_exchanges_name_exists(suite, cases):
    """Every ambiguity the exchange rules name is in the register, every bound an exchange, step or probe names is in
    the register of bounds (the lint refuses a bare number in a suite that has one), every capability has a service."""
    behaviour = suite.behaviour
    named = [r["ambiguity"] for r in behaviour["silence"]]
    for ex in behaviour["exchanges"]:
        named += [r["ambiguity"] for r in ex.get("silence", ())]
        state = ex.get("state", {})
        for states in (state, *state.get("by_request", {}).get("values", {}).values()):
            named += [*states.get("open", {}).values(), *([states["unknown"]] if "unknown" in states else ())]
        assert ex["within"] in behaviour["bounds"], ex["id"]
    assert named and set(named) <= set(behaviour["ambiguities"])
    assert {c["service"] for c in behaviour["capabilities"].values()} == set(behaviour["services"])
    probes = [c.data["probe"] for c in cases if c.kind == "robustness"]
    assert probes and all(p["within"] in behaviour["bounds"] for p in probes)
    case = next(c.data for c in cases if c.id == "imc/LblConfig/scenario/get-cfg")
    problem = suite.live_problem("scenario", dict(case, steps=[case["steps"][0], dict(case["steps"][1], within=5)]))
    assert problem[0] == ".steps[1].within" and "names its source" in problem[1]


def test_a_step_may_not_cover_an_unknown_or_untestable_statement(suite, cases):
    case = next(c.data for c in cases if c.id == "imc/LblConfig/scenario/get-cfg")
    for sid, why in (("LblConfig.nothing", "not a statement"), ("AcousticLink.report", "marked untestable")):
        broken = dict(case, steps=[dict(case["steps"][0]), dict(case["steps"][1], covers=[sid])])
        problem = suite.live_problem("scenario", broken)
        assert problem is not None and problem[0] == ".steps[1].covers[0]" and why in problem[1]


def test_a_must_step_needs_the_seeds_normative_words(suite, cases):
    """The lint: a MUST step that cites no MUST statement (the seed's normative text) is a corpus error; the same
    step at SHOULD is fine."""
    case = next(c.data for c in cases if c.id == "imc/LblConfig/scenario/get-cfg")
    for covers, level, refused in ((["LblConfig.set-no-ack"], "MUST", True), (["LblConfig.set-no-ack"], "SHOULD", False),
                                   (["LblConfig.get-cfg"], "MUST", False)):
        step = dict(case["steps"][1], covers=covers, level=level)
        problem = suite.live_problem("scenario", dict(case, steps=[case["steps"][0], step]))
        assert (problem is not None and "MUST statement" in problem[1]) == refused, (covers, level, problem)


def test_an_open_reading_must_be_in_the_register(suite, cases):
    announce = next(c.data for c in cases if c.id == "imc/Announce/scenario/well-formed")
    step = dict(announce["steps"][0], if_silent="no-such-reading")
    problem = suite.live_problem("scenario", dict(announce, steps=[step]))
    assert problem == (".steps[0].if_silent", "'no-such-reading' is not an entry of ambiguities.json")
    case = next(c.data for c in cases if c.id == "imc/AcousticOperation/scenario/msg-short")
    step = dict(case["steps"][1], if_silent="msg-short-reply")  # a reply's silence is the exchange's to allow
    problem = suite.live_problem("scenario", dict(case, steps=[case["steps"][0], step]))
    assert problem is not None and problem[0] == ".steps[1].if_silent"
    step = dict(case["steps"][1], on_state={"MSG_DONE": {"range": 0.0}, "SENT": {"range": 0.0}})
    problem = suite.live_problem("scenario", dict(case, steps=[case["steps"][0], step]))
    assert problem is not None and problem[0] == ".steps[1].on_state.SENT"


def test_one_of_several_matchers_must_hold():
    from imc_conformance.kinds.scenario.matchers import mismatch

    spec = {"any_of": [{"contains_message": {"abbrev": "LblRange", "fields": {"id": 2}}},
                       {"lacks_message": {"abbrev": "LblRange", "fields": {"id": 1}}}]}
    one = {"abbrev": "LblRange", "fields": {"id": 1, "range": 1.0}}
    two = {"abbrev": "LblRange", "fields": {"id": 2, "range": 1.0}}
    assert mismatch(None, spec) is None and mismatch([two], spec) is None and mismatch([one, two], spec) is None
    assert "holds no" in mismatch([one], spec) and " and " in mismatch([one], spec)


def test_the_scenario_set_runs_concurrently_on_protocol_time(suite, cases):
    """Independent scenarios run together and a released sequence frees the modem during its quiet period: the set
    costs its longest chain of protocol time, not the sum (virtual time: this is exact, not a timing test)."""
    result, link = run_virtual(suite, cases)
    alone = sum(c.timeline[-1]["t"] for c in result.cases if c.timeline and "/passive/" not in c.id)
    modem = sum(c.timeline[-1]["t"] for c in result.cases if c.timeline and "/passive/" not in c.id
                and "acoustic-modem" in next(k for k in cases if k.id == c.id).data.get("resources", ()))
    assert link.now() <= modem + 2.0 < alone  # only the scenarios sharing the modem take turns


def test_only_uniquely_correlated_sequences_may_release_their_resources(suite, cases):
    import copy

    case = copy.deepcopy(next(c.data for c in cases if c.id == "imc/AcousticOperation/scenario/range"))
    case["steps"][-1]["release"] = True
    problem = suite.live_problem("scenario", case)
    assert problem[0] == ".steps[1].release" and "no $unique value" in problem[1]
    two = copy.deepcopy(next(c.data for c in cases if c.id == "imc/AcousticRequest/scenario/two-at-once"))
    two["steps"][2]["release"] = True
    assert "only the last step that waits" in suite.live_problem("scenario", two)[1]


def test_echoed_requests_and_the_nodes_internal_traffic_are_not_taken_for_replies(suite, cases):
    """DUNE sends what its UDP transport lists to every contact: the session's own requests come back, and so do
    the node's internal messages, addressed to itself, and statuses nobody asked for (Iridium's EMPTY, req_id 0).
    Replies are matched on the header and tied to requests by their echoed values, so none of them misleads."""
    from imc_conformance.suites.imc import codec
    from imc_conformance.suites.imc.node import ReferenceNode
    from live_harness import NODE

    class ChattyNode(ReferenceNode):
        def receive(self, t, data, source):
            super().receive(t, data, source)
            try:
                codec.decode(self.defs, data)  # DUNE passes on what it decoded: a frame it drops is not echoed
            except ValueError:
                return
            if source in self.contacts.values():
                self._later(t, 0.001, source, data)  # the request itself, back to its sender
                internal = {"abbrev": "AcousticStatus", "header": {"timestamp": 0.0, "src": self.system, "src_ent": 43,
                                                                   "dst": self.system, "dst_ent": 44},
                            "fields": {"req_id": 7, "type": 1, "status": 1, "info": "", "range": 0.0}}
                self._later(t, 0.002, source, codec.encode(self.defs, internal, "le"))
                empty = {"abbrev": "IridiumTxStatus", "header": {"timestamp": 0.0, "src": self.system, "src_ent": 0,
                                                                 "dst": 0xFFFF, "dst_ent": 0xFF},
                         "fields": {"req_id": 0, "status": 6, "text": ""}}  # DUNE's periodic EMPTY, to anyone
                self._later(t, 0.003, source, codec.encode(self.defs, empty, "le"))

    node = ChattyNode(suite.defs, suite.behaviour, edition=suite.editions[0], address=NODE)
    from live_harness import virtual_session
    from imc_conformance.core.runner import run_cases

    session, link = virtual_session(suite, suite.editions[0], node=node)
    result = run_cases(session, suite, scenario_cases(cases), edition=suite.editions[0], adapter="virtual",
                       options=EVERYTHING, clock=link.now)
    assert {c.id: c.detail for c in result.cases if c.verdict not in (Verdict.PASS, Verdict.IMPL_DEFINED)} == {}
    readings = [k for c in result.cases for k in c.checks if k.verdict is Verdict.IMPL_DEFINED]
    assert readings and all(":reading-" in k.check and "open reading" in k.detail for k in readings)


@pytest.mark.parametrize("broken", ["req-id-not-echoed", "type-not-echoed", "wrong-system"])
def test_an_answer_echoing_another_value_decides_its_step_at_once(suite, cases, broken):
    """A reply addressed to the scenario's own entity is the answer to its request, whatever it echoes: the step
    fails then, instead of waiting out its bound (and its retries) for a reply that will never match. In protocol
    time (virtual), the whole set then takes about what it takes against the reference node."""
    _, clean = run_virtual(suite, cases)
    result, link = run_virtual(suite, cases, broken=broken)
    assert link.now() <= 2 * clean.now()
    caught, verdict = CAUGHT[broken]
    assert verdicts(result)[caught] == verdict
    assert "echoes" in next(c for c in result.cases if c.id == caught).detail


def test_every_variant_has_its_readings_listed():
    assert set(READINGS) == set(VARIANTS)


@pytest.mark.parametrize("variant", sorted(VARIANTS))
@pytest.mark.parametrize("edition", ["imc-5.4.30", "imc-5.4.11"])
def test_a_node_taking_another_reading_the_seeds_allow_gets_no_failure(suite, cases, variant, edition):
    """Proof the other way: a correct node that reads an open clause otherwise (ambiguities.json) is never FAILed,
    and not even under --strict, but for the silence of a node where the seeds define a reply they do not require (its
    register entry a SHOULD: NON_STRICT, each such check naming the entry); each other reading it takes is shown as an
    IMPL_DEFINED check naming the register's entry, and a request it declines where the seeds let it (UNSUPPORTED)
    shows the case UNSUPPORTED, declining."""
    result, _ = run_virtual(suite, cases, edition, variant=variant, strict=True)
    declined = {c.id for c in result.cases if c.verdict is Verdict.UNSUPPORTED
                and any(k.check.endswith(":declined") and k.verdict is Verdict.UNSUPPORTED for k in c.checks)}
    assert bool(declined) == (variant == "declines-reverse-range") and all("reverse-range" in c for c in declined)
    should = SILENT_WHERE_A_REPLY_IS_DEFINED.get(variant, set())
    unmet = {k.check.split(":reading-", 1)[1] for c in result.cases for k in c.checks if k.verdict is Verdict.NON_STRICT}
    assert unmet == should and all(":reading-" in k.check for c in result.cases for k in c.checks
                                   if k.verdict is Verdict.NON_STRICT)
    assert {c.id: c.detail for c in result.cases if c.verdict not in (Verdict.PASS, Verdict.IMPL_DEFINED)
            and c.id not in declined and not (c.verdict is Verdict.NON_STRICT and should)} == {}
    assert result.exit_code() == (1 if should else 0)  # a SHOULD not met fails under --strict
    taken = {k.check.split(":reading-", 1)[1] for c in result.cases for k in c.checks if ":reading-" in k.check}
    reference, _ = run_virtual(suite, cases, edition)
    assert ([c.timeline for c in result.cases] != [c.timeline for c in reference.cases]
            or result.notes != reference.notes)  # the variant took effect
    usual = {k.check.split(":reading-", 1)[1] for c in reference.cases for k in c.checks if ":reading-" in k.check}
    assert READINGS[variant] <= taken and taken - usual <= READINGS[variant], taken - usual
    register = suite.behaviour["ambiguities"]
    assert all(r in register for r in taken)


def test_a_malformed_answer_to_the_request_decides_its_step_at_once(suite, cases):
    """A node whose replies do not decode (big-endian with a little-endian CRC) but whose headers address the
    scenario's requester: each step is decided when that reply comes, not after its bound and retries; the verdicts
    are those the frames' own byte checks give."""
    result, link = run_virtual(suite, cases, broken="big-endian-le-crc")
    clean, clean_link = run_virtual(suite, cases)
    assert link.now() <= 2 * clean_link.now()
    case = next(c for c in result.cases if c.id == "imc/AcousticSystemsQuery/scenario/reply")
    assert case.verdict is Verdict.FAIL and "is malformed: crc" in case.detail
    assert verdicts(result)["imc/AcousticStatus/passive/AcousticRequest/scenario/range"] == "FAIL"


def test_a_counting_step_takes_only_what_its_only_holds_and_names_real_fields(suite, cases):
    """``only`` on an expect step: frames whose fields do not hold it are ignored (two RANGEs to one system: the
    progress states are not taken for terminal ones, so the reference node passes); the lint refuses a field the
    message lacks."""
    case = next(c.data for c in cases if c.id == "imc/AcousticOperation/scenario/two-ranges-one-system")
    step = dict(case["steps"][2], only={"nope": 1})
    problem = suite.live_problem("scenario", dict(case, steps=[*case["steps"][:2], step]))
    assert problem is not None and problem[0] == ".steps[2].only.nope" and "no field" in problem[1]
    result, _ = run_virtual(suite, cases, kinds=("scenario",))
    found = next(c for c in result.cases if c.id == case["id"])
    assert found.verdict is Verdict.PASS
    assert any(e.get("note") == "not what the step counts (its only)" for e in found.timeline)


def test_a_capability_judged_only_where_claimed_is_unsupported_without_claims(suite, cases):
    """LBL navigation (lbl-ranges): a node that does not navigate with LBL sends no LblRange, so without a claims file
    its scenario is not claimed (UNSUPPORTED), never a failure; claimed, a node that sends none is caught."""
    chosen = [c for c in cases if c.id == "imc/LblConfig/scenario/ranges-after-set"]
    options = {k: v for k, v in EVERYTHING.items() if k != "claims"}
    unclaimed, _ = run_virtual(suite, chosen, options=options, broken="no-lbl-ranges")
    case = next(c for c in unclaimed.cases if c.id == chosen[0].id)
    assert case.verdict is Verdict.UNSUPPORTED and "judged only where --claims claims it" in case.detail
    claimed, _ = run_virtual(suite, chosen, broken="no-lbl-ranges")
    assert verdicts(claimed)[chosen[0].id] == "NON_STRICT"


def test_a_lost_first_copy_is_resent_and_answered(suite, cases):
    """A targeted loss (loses-first-copy): the first copy of each idempotent request never reaches the node, so every
    answer a scenario gets to one comes after its resend, and nothing fails."""
    result, _ = run_virtual(suite, cases, variant="loses-first-copy")
    assert {c.id: c.detail for c in result.cases if c.verdict not in (Verdict.PASS, Verdict.IMPL_DEFINED)} == {}
    resent = {c.id for c in result.cases for e in c.timeline if e["event"] == "resent"}
    assert {"imc/HistoricDataQuery/scenario/query", "imc/AcousticSystemsQuery/scenario/reply",
            "imc/LblConfig/scenario/get-cfg"} <= resent


def test_a_node_forwarding_on_dunes_period_is_caught_only_if_it_forwards_an_expired_command(suite, cases):
    """The expiring command provoked: a node that forwards its kept commands every 30 s (as DUNE) passes; the same
    node checking a command's timeout only on arrival (as DUNE) forwards the expired one when its recipient appears."""
    chosen = [c for c in cases if c.id.startswith("imc/RemoteCommand/")]
    case_id = "imc/RemoteCommand/scenario/expires-before-recipient-appears"
    plain, _ = run_virtual(suite, chosen, variant="forwards-on-period")
    assert {c.id: c.verdict.value for c in plain.cases if c.verdict is not Verdict.PASS} == {}
    both, _ = run_virtual(suite, chosen, variant="forwards-on-period", broken="forwards-expired-stored")
    assert verdicts(both)[case_id] == "FAIL"


def test_silence_is_a_reading_only_for_a_request_about_the_group_disbanded(suite, cases):
    """A SystemGroup Req for a group a Dis of the same requester disbanded may go unanswered (reading
    disbanded-group-request), live and in the passive view of its frames; a Req for a group nobody disbanded (the Dis
    named another) that goes unanswered stays a SHOULD not met."""
    import copy
    from dataclasses import replace

    case = next(c for c in cases if c.id == "imc/SystemGroup/scenario/disband-then-request")
    result, _ = run_virtual(suite, [case], variant="silent-on-unknown-group")
    assert verdicts(result)[case.id] == "IMPL_DEFINED"
    assert not [c.id for c in result.cases if c.verdict in (Verdict.FAIL, Verdict.NON_STRICT)]
    data = copy.deepcopy(case.data)
    for step in data["steps"]:
        if "send" in step and step["id"] != "request":
            step["send"]["fields"]["GroupName"] = "imc-conformance-other-group"
    other, _ = run_virtual(suite, [replace(case, data=data)], variant="silent-on-unknown-group")
    found = next(c for c in other.cases if c.id == case.id)
    assert found.verdict is Verdict.NON_STRICT and "no SystemGroup" in found.detail


DUPLICATED = ("imc/AcousticSystemsQuery/scenario/duplicated-query", "imc/LblConfig/scenario/duplicated-get",
              "imc/SystemGroup/scenario/duplicated-request")


def test_a_duplicated_request_answered_once_or_twice_is_a_reading_and_a_third_reply_is_flagged(suite, cases):
    """A query the link duplicated: the reference node answers each copy, answers-a-copy-once only the first; each
    shows the reading duplicated-request and neither fails. A node that answers every query twice (four replies to
    the two copies) is flagged by the step that allows one more reply, not more (SHOULD)."""
    chosen = [c for c in cases if c.id in DUPLICATED]
    for variant, said in ((None, "answered too (a second reply): yes"), ("answers-a-copy-once", "no ")):
        result, _ = run_virtual(suite, chosen, variant=variant)
        for case in (c for c in result.cases if c.id in DUPLICATED):
            reading = next(k for k in case.checks if k.check == "step:copy-reply:reading-duplicated-request")
            assert case.verdict is Verdict.IMPL_DEFINED and said in reading.detail, (variant, case.id, reading.detail)
    twice, _ = run_virtual(suite, chosen, broken="two-replies")
    assert verdicts(twice)["imc/AcousticSystemsQuery/scenario/duplicated-query"] == "NON_STRICT"
