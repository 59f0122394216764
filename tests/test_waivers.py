"""Waivers never hide a broken adapter, and the files --write-waivers writes are ones the next run accepts and that
waive what they list: an ADAPTER_ERROR is never waived nor written; a run that judged nothing waives nothing; what
a case found about another message is waived through that case or its cause; the waived stay waived, the passing
get none, --strict writes its NON_STRICT cases; every report gives a waiver's reason; a shard leaves a waiver
another shard uses to the merge; a mistyped cause key is refused; many globs load in linear work."""

from __future__ import annotations

import datetime as dt
import json
import shlex
import sys
from pathlib import Path
from types import SimpleNamespace

import pytest

from imc_conformance.cli import main
from imc_conformance.core import waivers as waivers_module
from imc_conformance.core.cases import shard_of
from imc_conformance.core.causes import subjects
from imc_conformance.core.results import CheckResult, Judgement
from imc_conformance.core.runner import run_cases
from imc_conformance.core.session import Answer, Request
from imc_conformance.core.verdicts import Verdict
from imc_conformance.core.waivers import (Waiver, Waivers, cause_waivers_document, waivers_document,
                                          waivers_in_force)

HERE = Path(__file__).resolve().parent
CRC = "imc/LblRange/crc/*"  # pyimclsts checks no CRC: every case FAILs (erratum P1)
P1 = "imc/LblRange/crc/header-timestamp/le"
PASSING = "imc/LblRange/minimal"


def adapter_cmd(script: str, *args: str) -> list[str]:
    return ["--adapter-cmd", shlex.join([sys.executable, str(HERE / script), *args])]


BROKEN = adapter_cmd("broken_adapter.py")  # every answer its own failure: ADAPTER_ERROR
WRONG_RULE = adapter_cmd("wrong_adapter.py", "wrong-rule")  # names crc on every refusal: NON_STRICT


def run(*args) -> int:
    return main(["run", "--no-progress", *args])


def waivers_file(tmp_path: Path, *entries, name: str = "waivers.json") -> str:
    path = tmp_path / name
    path.write_text(json.dumps({"waivers": list(entries)}))
    return str(path)


def verdicts(path: Path) -> dict[str, str]:
    return {c["id"]: c["verdict"] for m in json.loads(path.read_text())["messages"] for c in m["cases"]}


def written(path: Path) -> list[dict]:
    return json.loads(path.read_text())["waivers"]


# ---------------------------------------------------------------- an ADAPTER_ERROR is never waived

@pytest.mark.parametrize("entry", [{"glob": "*"}, {"glob": CRC}, {"id": P1}, {"rule": "crc"}])
def test_no_waiver_covers_an_adapter_error(entry, tmp_path, capsys):
    result = tmp_path / "r.json"
    assert run(*BROKEN, "--id", CRC, "--waivers", waivers_file(tmp_path, {**entry, "reason": "r"}),
               "--json", str(result)) == 2
    assert set(verdicts(result).values()) == {"ADAPTER_ERROR"}


def test_write_waivers_offers_none_for_an_adapter_error_and_a_cause_waiver_of_one_is_refused(tmp_path, capsys):
    for by in ("case", "cause"):
        path = tmp_path / f"by-{by}.json"
        assert run(*BROKEN, "--id", CRC, "--write-waivers", str(path), "--by", by) == 2
        assert written(path) == []
        assert "no waiver written for 18 ADAPTER_ERROR cases" in capsys.readouterr().err
    cause = waivers_file(tmp_path, {"cause": "adapter_error/decode/rule:crc", "reason": "r"})
    assert run(*BROKEN, "--id", CRC, "--waivers", cause) == 2
    assert "is a cause no waiver covers: an adapter error says the adapter is broken" in capsys.readouterr().err


class Silent:
    """A live session that answers nothing (every case it is given needs a parameter not given: judged without it)."""

    name, stderr, incidents = "silent", "", []

    def hello(self) -> dict:
        return {"implementation": "silent node", "suites": ["imc"], "byte_orders": ["le", "be"], "kinds": ["scenario"]}

    def run(self, jobs):
        return iter(())

    def close(self) -> None:
        pass


def test_a_run_that_judged_nothing_waives_nothing_and_writes_no_waiver(suite, cases):
    needy = [c for c in cases if c.kind == "scenario" and c.data.get("needs")]
    result = run_cases(Silent(), suite, needy, edition="imc-5.4.30", adapter="silent", strict=True,
                       waivers=Waivers([Waiver("glob", "*", "everything")]))
    assert result.summary and set(result.summary) == {"INCONCLUSIVE"}  # failing under --strict, yet never WAIVED
    assert result.exit_code() == 2 and "no waiver applies: the run judged nothing" in result.notes
    doc, notes = waivers_document(result, "r")
    assert doc == {"waivers": []} and notes[0].startswith("no waiver written: nothing could be tested")


# ---------------------------------------------------------------- what --write-waivers writes

def test_write_waivers_keeps_the_waived_with_their_reason_and_none_for_a_passing_case(tmp_path, capsys):
    old = waivers_file(tmp_path, {"id": PASSING, "reason": "was broken once"},
                       {"glob": CRC, "reason": "pyimclsts checks no CRC (P1)"})
    new, result = tmp_path / "new.json", tmp_path / "r.json"
    assert run("--adapter", "pyimclsts", "--id", CRC, "--id", PASSING, "--waivers", old, "--write-waivers", str(new),
               "--json", str(result)) == 1  # the passing case's waiver is stale
    waived = sorted(i for i, v in verdicts(result).items() if v == "WAIVED")
    assert len(waived) == 18 and sorted(w["id"] for w in written(new)) == waived
    assert {w["reason"] for w in written(new)} == {"pyimclsts checks no CRC (P1)"}
    assert run("--adapter", "pyimclsts", "--id", CRC, "--id", PASSING, "--waivers", str(new)) == 0


@pytest.mark.parametrize("by", ["case", "cause"])
def test_strict_write_waivers_writes_the_non_strict_cases_and_the_next_strict_run_accepts_them(by, tmp_path, capsys):
    path, result = tmp_path / "w.json", tmp_path / "r.json"
    assert run(*WRONG_RULE, "--message", "LblRange", "--strict", "--write-waivers", str(path), "--by", by,
               "--json", str(result)) == 1
    non_strict = [i for i, v in verdicts(result).items() if v == "NON_STRICT"]
    assert non_strict and written(path)
    if by == "case":
        assert sorted(w["id"] for w in written(path)) == sorted(non_strict)
    assert run(*WRONG_RULE, "--message", "LblRange", "--strict", "--waivers", str(path), "--json", str(result)) == 0
    assert sorted(i for i, v in verdicts(result).items() if v == "WAIVED") == sorted(non_strict)


class Finder:
    """A case kind that answers its case's own check as ``own`` and files a FAIL about the bytes of a reply under
    AcousticSystems (as a scenario does of a malformed reply): what a live run finds passively."""

    name = "vector"

    def __init__(self, own: Verdict):
        self.own = own

    def plan(self, case, edition, emits, options):
        return [Request("decode-le", "decode", "le", frame=b"")]

    def judge(self, case, edition, request, answer):
        return Judgement([CheckResult("decode-le", self.own, "own check"),
                          CheckResult("bytes", Verdict.FAIL, "a malformed reply", clause="IMC-1",
                                      filed_under="AcousticSystems")])


class Answering:
    name, stderr, incidents = "finder", "", []

    def hello(self) -> dict:
        return {"implementation": "finder", "suites": ["imc"], "byte_orders": ["le", "be"]}

    def run(self, jobs):
        return ((job, Answer("ok")) for job in jobs)

    def close(self) -> None:
        pass


def finder_run(suite, cases, own: Verdict, waivers: Waivers | None = None):
    """A run of PASSING through ``Finder``: its own check ``own``, its finding about AcousticSystems a FAIL."""
    proxy = SimpleNamespace(name=suite.name, title=suite.title, groups=suite.groups, kinds={"vector": Finder(own)},
                            encodings=suite.encodings, encoding_param=suite.encoding_param,
                            implementation_errata=suite.implementation_errata)
    return run_cases(Answering(), proxy, [c for c in cases if c.id == PASSING], edition="imc-5.4.30",
                     adapter="finder", waivers=waivers)


@pytest.mark.parametrize("own", [Verdict.PASS, Verdict.FAIL])
@pytest.mark.parametrize("by", ["case", "cause"])
def test_a_finding_about_another_message_is_written_as_a_waiver_the_next_run_accepts_and_applies(suite, cases, own,
                                                                                                  by):
    first = finder_run(suite, cases, own)
    finding = "imc/AcousticSystems/passive/LblRange/minimal"
    assert {c.id: c.verdict for c in first.cases}[finding] is Verdict.FAIL and first.exit_code() == 1
    data = {c.id: c.data for c in cases if c.id == PASSING}
    doc, _ = (waivers_document(first, "r") if by == "case" else cause_waivers_document(first, "r", data))
    if by == "case":
        assert doc["waivers"] == [{"id": PASSING, "reason": "r"}]  # through the case that made it
    else:
        assert "fails/bytes/family:passive" in [w.get("cause") for w in doc["waivers"]]
    rules = set(suite.kinds["vector"].codec.rules)
    active, _ = waivers_in_force(doc, {c.id for c in cases}, rules, subjects(cases), dt.date.today(), "w")
    again = finder_run(suite, cases, own, active)
    found = {c.id: c for c in again.cases}
    assert found[finding].verdict is Verdict.WAIVED and found[finding].waiver
    assert found[PASSING].verdict is (Verdict.PASS if own is Verdict.PASS else Verdict.WAIVED)  # never stale
    assert again.exit_code() == 0 and not again.stale_waivers


# ---------------------------------------------------------------- a waiver's reason in every report

def test_a_waivers_reason_is_in_every_report(tmp_path, capsys):
    reason = "pyimclsts checks no CRC, ticket 1234"
    path = waivers_file(tmp_path, {"glob": CRC, "reason": reason})
    reports = {kind: tmp_path / f"r.{kind}" for kind in ("json", "junit", "markdown", "html")}
    assert run("--adapter", "pyimclsts", "--id", CRC, "--waivers", path,
               *(a for kind, p in reports.items() for a in (f"--{kind}", str(p)))) == 0
    assert reason in " ".join(capsys.readouterr().out.split())  # the terminal's lines wrap
    for kind, report in reports.items():
        assert reason in report.read_text(), kind
    assert main(["report", str(reports["json"])]) == 0
    assert reason in " ".join(capsys.readouterr().out.split())


# ---------------------------------------------------------------- shards

def test_a_shard_never_exits_1_on_a_waiver_another_shard_uses(tmp_path, capsys):
    n = next(n for n in range(2, 64) if shard_of(P1, n) != shard_of(PASSING, n))  # the two in different shards
    selection = ("--adapter", "pyimclsts", "--id", P1, "--id", PASSING)
    path = waivers_file(tmp_path, {"glob": "imc/LblRange/*", "reason": "r"})  # P1's shard uses it, PASSING's not
    shards = [str(tmp_path / f"s{k}.json") for k in range(1, n + 1)]
    for k, shard in enumerate(shards, 1):
        assert run(*selection, "--shard", f"{k}/{n}", "--waivers", path, "--json", shard) == 0
    notes = json.loads(Path(shards[shard_of(PASSING, n) - 1]).read_text())["notes"]
    assert any(f"names cases of the run but waives none of shard {shard_of(PASSING, n)}/{n}'s" in note
               for note in notes)
    assert main(["report", "--merge", *shards]) == 0
    for k, shard in enumerate(shards, 1):  # imcpy checks the CRC: no shard uses the waiver
        assert run(*selection, "--adapter", "imcpy", "--shard", f"{k}/{n}", "--waivers", path, "--json", shard) == 0
    capsys.readouterr()
    assert main(["report", "--merge", *shards]) == 1  # the merge of every shard decides
    assert "WAIVER_STALE: the waiver of glob imc/LblRange/* names cases of this run" in \
        " ".join(capsys.readouterr().out.split())


# ---------------------------------------------------------------- loading

@pytest.mark.parametrize("key, error", [
    ("accept/rule:crc", "'accept/rule:crc' is not a cause key of this corpus (it begins with 'accept'"),
    ("accepts/decode/rule:crc", "a key beginning with 'accepts' is accepts/SUBJECT"),
    ("fails/rule:crc", "a key beginning with 'fails' is fails/OPERATIONS/SUBJECT"),
])
def test_a_mistyped_cause_key_is_not_a_cause_key(key, error, tmp_path, capsys):
    assert run("--adapter", "pyimclsts", "--id", CRC, "--waivers", waivers_file(tmp_path, {"cause": key,
                                                                                         "reason": "r"})) == 2
    assert error in capsys.readouterr().err


def test_twenty_thousand_globs_load_and_apply_in_work_linear_in_their_number(cases, suite, monkeypatch):
    ids = sorted(c.id for c in cases)
    globs = list(dict.fromkeys(g for i in ids if not any(c in i for c in "*?[]") for g in (i + "*", i[:-1] + "?", i[:-1] + "[" + i[-1] + "]",
                                                        i + "**", i[:-1] + "*")))[:20_000]
    assert len(globs) == 20_000
    budget = 8 * (len(globs) + len(ids))
    calls = []

    def counted(name, pattern):
        calls.append(1)
        if len(calls) > budget:
            raise AssertionError(f"over {budget} glob matches for {len(globs)} globs and {len(ids)} cases")
        return real(name, pattern)

    real = waivers_module.fnmatchcase
    monkeypatch.setattr(waivers_module, "fnmatchcase", counted)
    doc = {"waivers": [{"glob": g, "reason": "r"} for g in globs]}
    active, _ = waivers_in_force(doc, set(ids), set(), subjects(cases), dt.date.today(), "w")
    found = {i: active.find(i, None, "valid", "fails/decode/valid") for i in ids}
    made = set(globs)
    assert all(found[i] is not None for i in ids if i + "*" in made) and len(made) == len(globs)
    assert len(active) == 20_000


@pytest.mark.parametrize("by", ["case", "cause"])
def test_a_live_runs_finding_about_a_malformed_reply_is_waived_by_the_file_written_from_it(suite, cases, by):
    """Against a node whose AcousticSystems replies are malformed, the finding is filed under AcousticSystems by the
    AcousticSystemsQuery scenario that got it (virtual time: tests/live_harness.py)."""
    from live_harness import EVERYTHING, scenario_cases, virtual_session

    chosen = [c for c in scenario_cases(cases) if c.group == "AcousticSystemsQuery"]

    def live(waivers=None):
        session, link = virtual_session(suite, "imc-5.4.30", broken="malformed-reply")
        return run_cases(session, suite, chosen, edition="imc-5.4.30", adapter="virtual", options=dict(EVERYTHING),
                         clock=link.now, started="2026-01-01T00:00:00+00:00", waivers=waivers)

    first = live()
    finding = "imc/AcousticSystems/passive/AcousticSystemsQuery/scenario/reply"
    assert {c.id: c.verdict for c in first.cases}[finding] is Verdict.FAIL and first.exit_code() == 1
    data = {c.id: c.data for c in chosen}
    doc, _ = waivers_document(first, "r") if by == "case" else cause_waivers_document(first, "r", data)
    rules = set(suite.kinds["vector"].codec.rules)
    active, _ = waivers_in_force(doc, {c.id for c in cases}, rules, subjects(cases), dt.date.today(), "w")
    again = live(active)
    assert {c.id: c.verdict for c in again.cases}[finding] is Verdict.WAIVED
    assert again.exit_code() == 0 and not again.stale_waivers
