"""The debugging loop: ``run --last-failed FILE`` runs again exactly the cases that did not pass in a saved result (of
a byte run and of a live run), and ``run --exitfirst`` stops at the first failing case. The live runs go through
the command line with the reference node, broken, on virtual time instead of UDP (no timing in these tests)."""

from __future__ import annotations

import json

import pytest

from imc_conformance import live
from imc_conformance.cli import main
from imc_conformance.core.cases import source_case
from imc_conformance.core.results import RunResult
from imc_conformance.render.markdown import render_markdown
from imc_conformance.core.verdicts import ATTENTION, FAILING
from live_harness import PARAMS, virtual_session

LIVE = ["--target", "udp://127.0.0.1:9", "--allow-effects",
        *[a for k, v in PARAMS.items() for a in ("--param", f"{k}={v}")]]
BROKEN = "req-id-not-echoed"  # fails some scenarios of these messages at once, passes the others
MESSAGES = ["--message", "AcousticSystemsQuery", "--message", "HistoricDataQuery", "--message", "IridiumMsgTx"]


def saved(path) -> dict[str, str]:
    """A saved result's verdicts by case id."""
    doc = json.loads(path.read_text(encoding="utf-8"))
    return {c["id"]: c["verdict"] for m in doc["messages"] for c in m["cases"]}


def not_passed(verdicts: dict[str, str]) -> set[str]:
    return {i for i, v in verdicts.items() if v in {a.value for a in ATTENTION}}


@pytest.fixture
def broken_node(monkeypatch, suite):
    """``--target`` reaches the reference node broken as BROKEN, on virtual time."""
    monkeypatch.setattr(live, "open_target", lambda args, suite_, recorder=None: virtual_session(
        suite, args.edition, broken=BROKEN)[0])


def test_last_failed_reruns_exactly_the_failing_cases_of_a_byte_run(tmp_path, capsys):
    first, again = tmp_path / "first.json", tmp_path / "again.json"
    assert main(["run", "--adapter", "pyimclsts", "--message", "LblRange", "--message", "LblConfig", "--no-progress",
                 "--json", str(first)]) == 1
    before = saved(first)
    failed = not_passed(before)
    assert failed and len(failed) < len(before)
    assert main(["run", "--adapter", "pyimclsts", "--last-failed", str(first), "--no-progress",
                 "--json", str(again)]) == 1
    after = saved(again)
    assert set(after) == failed and after == {i: before[i] for i in failed}
    doc = json.loads(again.read_text(encoding="utf-8"))
    assert doc["notes"][0] == f"run again: {len(failed)} of the {len(failed)} cases that did not pass in {first}"
    assert doc["provenance"]["selection"]["last_failed"] == str(first)
    # narrowed further by the usual selection
    assert main(["run", "--adapter", "pyimclsts", "--last-failed", str(first), "--message", "LblRange", "--no-progress",
                 "--json", str(again)]) == 1
    assert set(saved(again)) == {i for i in failed if i.split("/")[1] == "LblRange"}
    # without an adapter named, the one that judged them (pyimclsts), not the suite's default (imcpy, which passes them)
    assert main(["run", "--last-failed", str(first), "--no-progress", "--json", str(again)]) == 1
    assert saved(again) == {i: before[i] for i in failed}
    assert json.loads(again.read_text(encoding="utf-8"))["adapter"] == "pyimclsts"


def test_last_failed_through_a_program_needs_the_program_again(tmp_path, capsys):
    """A result judged through --adapter-cmd holds no way to start that program: one line asks for it."""
    first = tmp_path / "first.json"
    assert main(["run", "--adapter", "pyimclsts", "--message", "LblRange", "--no-progress", "--json", str(first)]) == 1
    capsys.readouterr()
    doc = json.loads(first.read_text(encoding="utf-8"))
    first.write_text(json.dumps(doc | {"adapter": "java -jar adapter.jar"}), encoding="utf-8")
    assert main(["run", "--last-failed", str(first), "--no-progress"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "give the same --adapter-cmd, --adapter-socket or --target" in err[0], err


def test_last_failed_reruns_exactly_the_cases_of_a_live_run_that_did_not_pass(tmp_path, broken_node, capsys):
    first, again = tmp_path / "first.json", tmp_path / "again.json"
    assert main(["run", "--no-progress", *LIVE, *MESSAGES, "--json", str(first)]) == 1
    before = saved(first)
    failed = not_passed(before)
    scenarios = {i for i in before if "/passive/" not in i}
    assert failed and {source_case(i) for i in failed} < scenarios  # some pass
    assert main(["run", "--no-progress", *LIVE, "--last-failed", str(first), "--json", str(again)]) == 1
    after = saved(again)
    # each scenario that did not pass (or whose finding about a reply did not) ran again, and nothing else did
    assert {source_case(i) for i in after} == {source_case(i) for i in failed}
    assert not_passed(after) == failed and all(after[i] == before[i] for i in failed)


def test_nothing_to_run_again_exits_0_and_a_wrong_result_is_a_usage_error(tmp_path, capsys):
    passed, other = tmp_path / "passed.json", tmp_path / "other.json"
    assert main(["run", "--adapter", "imcpy", "--message", "LblRange", "--tag", "valid", "--no-progress",
                 "--json", str(passed)]) == 0
    assert main(["run", "--adapter", "imcpy", "--last-failed", str(passed), "--no-progress"]) == 0
    assert "nothing to run again" in capsys.readouterr().out
    assert main(["run", "--suite", "ros_acomms", "--last-failed", str(passed), "--no-progress"]) == 2
    assert "a result of the suite 'imc', not of 'ros_acomms'" in capsys.readouterr().err
    other.write_text("{not json", encoding="utf-8")
    assert main(["run", "--last-failed", str(other), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "--last-failed: cannot read the result" in err and len(err.strip().splitlines()) == 1


def test_exitfirst_stops_a_live_run_at_the_first_failing_case(tmp_path, broken_node, capsys):
    whole, first = tmp_path / "whole.json", tmp_path / "first.json"
    assert main(["run", "--no-progress", *LIVE, *MESSAGES, "--json", str(whole)]) == 1
    assert main(["run", "--no-progress", *LIVE, *MESSAGES, "--exitfirst", "--json", str(first)]) == 1
    everything, stopped = saved(whole), saved(first)
    failing = {i for i, v in stopped.items() if v in {f.value for f in FAILING}}
    assert len({source_case(i) for i in failing}) == 1 and len(stopped) < len(everything)
    assert stopped == {i: everything[i] for i in stopped}  # what was done by then, judged as in the whole run
    note = json.loads(first.read_text(encoding="utf-8"))["notes"][0]
    assert note.startswith(f"stopped at the first failing case, {source_case(failing.pop())}: ")


def test_exitfirst_stops_a_byte_run_at_the_first_failing_case(tmp_path, capsys):
    path = tmp_path / "r.json"
    assert main(["run", "--adapter", "pyimclsts", "--message", "LblRange", "-x", "--no-progress",
                 "--json", str(path)]) == 1
    verdicts = list(saved(path).values())
    assert verdicts[-1] in {f.value for f in FAILING} and len(verdicts) < 40
    assert all(v not in {f.value for f in FAILING} for v in verdicts[:-1])
    doc = json.loads(path.read_text(encoding="utf-8"))
    assert doc["complete"] is False and doc["exit_code"] == 1  # only part of the selection, and no interruption
    back = RunResult.from_dict(doc)
    assert back.stopped and back.exit_code() == 1
    assert "Incomplete run**: it stopped at its first failing case" in render_markdown(back)
