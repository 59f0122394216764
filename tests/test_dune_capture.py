"""Real DUNE traffic, recorded by ``make dune-conformance --no-robustness`` (``run --pcap``, in its network namespace;
DUNE from the imcpy 1.1.2 sdist as lauv-simulator-1, the seed profile's scenarios, DUNE's claims: AcousticRequest only
for itself): the pcap command replays the scenario engine over it and gives the live run's verdicts, and the passive
exchange rules find in the bare frames what the scenarios found. Why DUNE fails what it fails is in the manual's DUNE
page (docs/how-to/dune.md), with DUNE's source lines."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from imc_conformance.cli import main

RECORDING = Path(__file__).parent / "data" / "dune-seed.pcapng"

# What the live run said (dune-seed.json of the recording run); every other scenario case is PASS.
NOT_PASS = {
    "imc/SmsTx/scenario/state": "UNSUPPORTED",  # not claimed: no GSM modem in the simulation
    "imc/SystemGroup/scenario/set-then-request": "UNSUPPORTED",  # not claimed: no DUNE task handles it
    "imc/HistoricDataQuery/scenario/sample-priority": "FAIL",  # DataStore transmits the -127 sample
    # recorded when the scenario's samples were 40 bytes: DUNE answered that max_size with no data, a SHOULD not met
    "imc/HistoricDataQuery/scenario/sample-order": "NON_STRICT",
    "imc/RemoteCommand/scenario/forwarded": "NON_STRICT",  # kept apart and forwarded by another route
    "imc/LblConfig/scenario/set-for-another-system": "NON_STRICT",  # a SET_CFG is applied whatever its destination
    "imc/LblConfig/scenario/unannounced-sender": "IMPL_DEFINED",  # served only once announced: a reading
    # no report where the seed defines one (UNSUPPORTED, MSG_FAILURE) without requiring it: a SHOULD not met, with its
    # register entry (ambiguities.json, level SHOULD), never failed
    "imc/AcousticOperation/scenario/reverse-range": "NON_STRICT",  # UAN does not implement REVERSE_RANGE
    "imc/AcousticOperation/scenario/msg-short": "NON_STRICT",  # CommManager drops it without a reply
    "imc/AcousticOperation/scenario/msg-without-message": "NON_STRICT",  # the CommManager task dies on it
    "imc/AcousticOperation/scenario/unsupported-op": "NON_STRICT",
    # DUNE honours an AcousticRequest only from its own system: its claims say so, so none was sent
    **{f"imc/AcousticRequest/scenario/{name}": "UNSUPPORTED" for name in (
        "range", "range-big-endian", "reverse-range", "msg", "abort", "raw-without-devdatabinary",
        "msg-without-message", "unknown-destination", "two-at-once", "raw", "timeout", "reused-id")},
    # the same, seen by the passive exchange rules in the bare frames
    **{f"imc/AcousticOperation/capture/exchange/acoustic-operation/reading/{name}": "NON_STRICT" for name in (
        "reverse-range-reply", "msg-short-reply", "msg-without-message")},
}
MESSAGES = {"Heartbeat": "PASS", "Announce": "PASS", "SmsTx": "UNSUPPORTED", "IridiumMsgTx": "PASS",
            "IridiumTxStatus": "PASS", "SystemGroup": "UNSUPPORTED", "HistoricData": "PASS", "HistoricDataQuery": "FAIL",
            "RemoteCommand": "PASS", "LblConfig": "PASS", "AcousticOperation": "PASS", "AcousticSystemsQuery": "PASS",
            "AcousticSystems": "PASS", "AcousticRequest": "UNSUPPORTED", "AcousticStatus": "PASS"}


@pytest.fixture(scope="module")
def judged(tmp_path_factory):
    out = tmp_path_factory.mktemp("dune") / "r.json"
    code = main(["pcap", str(RECORDING), "--json", str(out)])
    return code, json.loads(out.read_text())


def test_the_recording_is_small_enough_to_keep():
    assert RECORDING.stat().st_size < 1_000_000


def test_dune_replayed_gives_the_live_verdicts(judged):
    code, doc = judged
    verdicts = {c["id"]: c["verdict"] for m in doc["messages"] for c in m["cases"]}
    scenarios = {k: v for k, v in verdicts.items() if "/scenario/" in k}
    assert len(scenarios) == 107
    assert {k: v for k, v in verdicts.items() if v != "PASS"} == NOT_PASS
    assert {m["name"]: m["verdict"] for m in doc["messages"]} == MESSAGES
    assert code == 1
    assert not [n for n in doc["notes"] if n.startswith(("the replay sent", "the recording ends before"))]


def test_dune_frames_are_all_valid(judged):
    _, doc = judged
    frames = {c["id"]: c for m in doc["messages"] for c in m["cases"] if "/capture/frame/" in c["id"]}
    assert frames and all(c["id"].endswith("/frame/valid") and c["verdict"] == "PASS" for c in frames.values())
    assert doc["notes"][0].startswith("1,076 records, 1,076 datagrams on the ports judged")


def test_the_passive_rules_find_every_exchange_answered_or_an_open_reading(judged):
    """Every request DUNE got was answered, bar the AcousticOperations whose report the seed defines but does not
    require (their register entries, NON_STRICT). Of
    the 8 AcousticSystemsQuery, 7 are exchanges: the one to system 0 (no system in particular) counts as answered by
    DUNE; the one to the session's second system comes from that system's own address (one socket), so the rules take
    it for a frame echoed back, not a request."""
    _, doc = judged
    exchanges = {c["id"]: c for m in doc["messages"] for c in m["cases"] if "/capture/exchange/" in c["id"]}
    answered = {k: c for k, c in exchanges.items() if k.endswith("/answered")}
    assert len(answered) >= 6 and all(c["verdict"] == "PASS" for c in answered.values())
    systems = answered["imc/AcousticSystemsQuery/capture/exchange/acoustic-systems/answered"]
    assert next(k for k in systems["checks"] if k["check"] == "count")["detail"].startswith("7 exchanges")
    assert {k for k, c in exchanges.items() if c["verdict"] != "PASS"} == {
        f"imc/AcousticOperation/capture/exchange/acoustic-operation/reading/{name}" for name in (
            "reverse-range-reply", "msg-short-reply", "msg-without-message")}


WHOLE = Path(__file__).parent / "data" / "dune-whole.pcap"
# python -m imc_conformance.suites.imc.dune record --seconds 60 --per-message 40: what DUNE (lauv-simulator-1, its
# own list of transported messages) sent in a minute, at most 40 datagrams of each message
WHOLE_FRAMES = {"EntityState": 40, "CpuUsage": 11, "SimulatedState": 30, "StorageUsage": 3, "LogBookEntry": 10,
                "Heartbeat": 40, "Announce": 30, "Rpm": 40, "GpsFix": 40, "EulerAngles": 40, "AngularVelocity": 40,
                "Acceleration": 40, "Distance": 20, "Temperature": 13, "Salinity": 40, "ServoPosition": 40,
                "EstimatedState": 40, "AlignmentState": 23, "VehicleState": 40, "VehicleMedium": 40,
                "PlanControlState": 40}


def test_dunes_whole_traffic_is_judged_message_by_message_with_the_whole_protocol(tmp_path, capsys):
    assert main(["pcap", str(WHOLE), "--json", str(tmp_path / "seed.json")]) == 0
    assert "590 frames of 19 messages the suite does not cover" in capsys.readouterr().out
    assert main(["pcap", str(WHOLE), "--suite", "imc-full", "--json", str(tmp_path / "whole.json")]) == 0
    doc = json.loads((tmp_path / "whole.json").read_text())
    assert {m["name"]: [(c["id"], c["verdict"]) for c in m["cases"]] for m in doc["messages"]} == {
        name: [(f"imc/{name}/capture/frame/valid", "PASS")] for name in WHOLE_FRAMES}
    counts = {m["name"]: m["cases"][0]["detail"].split(" frame")[0].removeprefix("count: ") for m in doc["messages"]}
    assert counts == {name: str(n) for name, n in WHOLE_FRAMES.items()}
    assert not any("does not cover" in note for note in doc["notes"])
