"""What DUNE gets, per message and profile, and the defects the suite must go on catching: run by
``make dune-conformance`` over the reports it just wrote (not by CI, which does not build DUNE; the name keeps
pytest's collection of tests/ from picking it up). A change to the scenarios that stops catching a DUNE defect, or
starts failing something DUNE does right, fails here.

DUNE as shipped in the imcpy 1.1.2 sdist, configured by ``conformance/suites/imc/dune/world.py``.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

REPORTS = Path(os.environ.get("IMC_CONFORMANCE_DUNE_REPORTS", "reports"))
pytestmark = pytest.mark.skipif(not (REPORTS / "dune-seed.json").exists(),
                                reason="run by make dune-conformance, over the reports it writes")

# Per profile: the verdict of each message, and the cases whose verdict is a known DUNE behaviour.
MESSAGES = {  # SmsTx, SystemGroup: not claimed; AcousticRequest: claimed only for DUNE's own system (conformance.py)
    profile: {"Heartbeat": "FAIL", "Announce": "PASS", "SmsTx": "UNSUPPORTED", "IridiumMsgTx": "FAIL", "IridiumTxStatus": "PASS",
              "SystemGroup": "UNSUPPORTED", "HistoricData": "PASS", "HistoricDataQuery": "FAIL", "RemoteCommand": "FAIL",
              "LblConfig": "FAIL", "AcousticOperation": "FAIL", "AcousticSystemsQuery": "FAIL", "AcousticSystems": "PASS",
              "AcousticRequest": "UNSUPPORTED"}
    for profile in ("seed", "dune")
}
DEFECTS = {  # case -> (verdict under both profiles, words its detail must hold)
    "imc/AcousticOperation/scenario/unsupported-op": ("NON_STRICT", "no AcousticOperation"),
    "imc/HistoricDataQuery/scenario/sample-priority": ("FAIL", "holds {'abbrev': 'LblRange'"),  # DataStore.hpp:121-146
    "imc/Heartbeat/robustness/still-served": ("FAIL", "imc/HistoricData/"),  # DataStore.hpp:139-143: a wrong-typed sample
    # DUNE/Navigation/BasicNavigation.cpp:706-717: a SET_CFG is applied whatever its destination (UDP/Listener.hpp:146-153)
    "imc/LblConfig/scenario/set-for-another-system": ("NON_STRICT", "imc-conformance-elsewhere"),
    # DataStore.hpp:221-247: pollCommands hands out a stored command whatever its timeout (checked only on arrival)
    "imc/RemoteCommand/scenario/expires-before-recipient-appears": ("FAIL", "HistoricData received"),
    # DataStore.hpp:66, 121-146: every stored sample gets priority -1, so the priority-1 one may go first
    "imc/HistoricDataQuery/scenario/sample-order-rounds": ("FAIL", "step:reply:fields"),
}
READINGS = {  # case -> the open reading (ambiguities.json) DUNE takes: IMPL_DEFINED, never a failure
    "imc/LblConfig/scenario/unannounced-sender": "unannounced-sender",  # UDP/Listener.hpp:146-153: only announced contacts
    "imc/HistoricDataQuery/scenario/clear-after-handed": "clear-scope",  # DataStore/Task.cpp:363-410: per requester
    "imc/LblConfig/scenario/out-of-range-beacon": "out-of-range-beacon",  # the beacon at 2.0 rad kept as set
    "imc/HistoricDataQuery/scenario/query-empty-store": "empty-store-reply",  # DataStore/Task.cpp:373-380: no data set
    "imc/AcousticOperation/scenario/msg-to-unreachable-end": "msg-to-unreachable",  # MSG_FAILURE
}
UNMET = {  # case -> the register entry (level SHOULD) of a silence where the seed defines a reply: NON_STRICT
    "imc/AcousticOperation/scenario/reverse-range": "reverse-range-reply",  # UAN/Task.cpp:303-315: no report
    "imc/AcousticOperation/scenario/msg-short": "msg-short-reply",  # CommManager/Task.cpp:786-791: dropped
    "imc/AcousticOperation/scenario/msg-without-message": "msg-without-message",  # CommManager/Task.cpp:765-767: the task dies
}
ROBUSTNESS_ONLY = {"Heartbeat", "IridiumMsgTx", "LblConfig", "AcousticOperation", "AcousticSystemsQuery"}  # fail by it alone
PASSES = ("imc/AcousticOperation/scenario/range", "imc/AcousticOperation/scenario/msg", "imc/AcousticOperation/scenario/abort",
          "imc/AcousticOperation/scenario/unknown-system", "imc/AcousticOperation/scenario/abort-unreachable",
          "imc/AcousticOperation/scenario/msg-to-unreachable", "imc/AcousticSystemsQuery/scenario/lists-peer",
          "imc/LblConfig/scenario/set-then-get", "imc/LblConfig/scenario/set-replaces",
          "imc/LblConfig/scenario/cur-cfg-is-a-reply", "imc/LblConfig/scenario/unknown-op",
          "imc/HistoricDataQuery/scenario/max-size", "imc/HistoricDataQuery/scenario/sample-order",
          "imc/RemoteCommand/scenario/executed", "imc/RemoteCommand/scenario/expires-while-stored",
          "imc/IridiumMsgTx/scenario/status", "imc/IridiumMsgTx/scenario/ttl", "imc/Announce/scenario/well-formed",
          "imc/AcousticSystemsQuery/scenario/two-clients", "imc/RemoteCommand/scenario/forwarded-to-recipient",
          "imc/Heartbeat/scenario/periodic", "imc/AcousticSystemsQuery/scenario/reply",
          "imc/AcousticSystemsQuery/scenario/to-anyone", "imc/AcousticSystemsQuery/scenario/to-another-system",
          "imc/AcousticSystemsQuery/scenario/to-system-zero", "imc/LblConfig/scenario/duplicated-set",
          "imc/LblConfig/scenario/spoofed-own-source", "imc/HistoricDataQuery/scenario/many-at-once",
          "imc/HistoricDataQuery/scenario/keeps-producer", "imc/RemoteCommand/scenario/not-executed-for-another",
          # CommManager dies on a MSG without its message and is restarted at once (CommManager/Task.cpp:764-767,
          # DUNE/Tasks/Task.cpp:430-436): the acoustic service answers again 20 s later
          "imc/AcousticOperation/scenario/msg-without-message-then-served",
          "imc/AcousticOperation/scenario/msg-short-then-served", "imc/AcousticOperation/scenario/reverse-range-then-served",
          "imc/AcousticOperation/scenario/unsupported-op-then-served",
          "imc/AcousticOperation/scenario/range-outlives-msg-without-message",  # the RANGE ends all the same
          # Simulators.Iridium reports ERROR at once when the slow gateway does not answer: nothing after the ttl
          "imc/IridiumMsgTx/scenario/gateway-slow-then-back")


def result(profile: str) -> dict:
    return json.loads((REPORTS / f"dune-{profile}.json").read_text(encoding="utf-8"))


def cases(profile: str) -> dict[str, dict]:
    return {c["id"]: c for m in result(profile)["messages"] for c in m["cases"]}


def with_robustness(profile: str) -> bool:
    """Whether the run had the robustness phase (make dune-conformance --no-robustness leaves it out)."""
    return any("/robustness/" in case_id for case_id in cases(profile))


@pytest.mark.parametrize("profile", sorted(MESSAGES))
def test_each_message_gets_its_known_verdict(profile):
    doc = result(profile)
    assert doc["complete"] and f"profile: {profile}" in doc["notes"]  # the dune profile's practice note comes first
    expected = dict(MESSAGES[profile])
    if not with_robustness(profile):
        expected.update({name: "PASS" for name in ROBUSTNESS_ONLY})
    assert {m["name"]: m["verdict"] for m in doc["messages"]} == expected


@pytest.mark.parametrize("profile", sorted(MESSAGES))
def test_the_known_dune_defects_are_still_caught(profile):
    found = cases(profile)
    for case_id, (verdict, words) in DEFECTS.items():
        if "/robustness/" in case_id and not with_robustness(profile):
            continue
        assert found[case_id]["verdict"] == verdict and words in found[case_id]["detail"], case_id


def assert_readings(profile: str, readings: dict[str, str], verdict: str) -> None:
    """Each case of ``readings`` has ``verdict``, given by a check of its reading of that register entry."""
    found = cases(profile)
    for case_id, ambiguity in readings.items():
        checks = found[case_id]["checks"]
        assert found[case_id]["verdict"] == verdict, case_id
        assert any(k["check"].endswith(f":reading-{ambiguity}") and k["verdict"] == verdict for k in checks), case_id


@pytest.mark.parametrize("profile", sorted(MESSAGES))
def test_the_readings_dune_takes_are_shown_not_failed(profile):
    assert_readings(profile, READINGS, "IMPL_DEFINED")


@pytest.mark.parametrize("profile", sorted(MESSAGES))
def test_dunes_silence_where_the_seed_defines_a_reply_is_a_should_not_met(profile):
    assert_readings(profile, UNMET, "NON_STRICT")


@pytest.mark.parametrize("profile", sorted(MESSAGES))
def test_what_dune_does_right_passes(profile):
    found = cases(profile)
    assert {c: found[c]["verdict"] for c in PASSES} == {c: "PASS" for c in PASSES}


@pytest.mark.parametrize("profile", sorted(MESSAGES))
def test_what_dune_serves_only_to_itself_is_not_claimed_never_failed(profile):
    acoustic_request = {c: v for c, v in cases(profile).items() if c.startswith("imc/AcousticRequest/")}
    assert acoustic_request and {v["verdict"] for v in acoustic_request.values()} == {"UNSUPPORTED"}
    assert all("only to its own system" in v["detail"] for v in acoustic_request.values())


@pytest.mark.parametrize("profile", sorted(MESSAGES))
def test_dune_goes_on_serving_after_everyday_traffic(profile):
    """The hostile blocks (requests to anyone, to 0, to another system, from its own id or an unannounced system,
    duplicated, reusing ids, many at once): every probe still answered."""
    if not with_robustness(profile):
        return
    hostile = [k for c in cases(profile).values() for k in c["checks"] if k["check"] == "probe:hostile"]
    assert hostile and all(k["verdict"] == "PASS" for k in hostile)


def test_the_dune_profile_excuses_only_what_it_cites():
    seed, dune = cases("seed"), cases("dune")
    changed = {c for c in seed if c in dune and seed[c]["verdict"] != dune[c]["verdict"]}
    assert changed == {"imc/RemoteCommand/scenario/forwarded"} and dune["imc/RemoteCommand/scenario/forwarded"]["verdict"] == "INCONCLUSIVE"


def test_the_run_left_no_process_behind():
    from imc_conformance.suites.imc.dune.world import leftovers

    assert leftovers() == []
    codes = json.loads((REPORTS / "dune-run.json").read_text())["exit_codes"]
    assert {p: codes[p] for p in MESSAGES} == {"seed": 1, "dune": 1} and codes.get("fuzz", 0) == 0
