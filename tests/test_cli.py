"""The command line: exit codes, waivers, reports, re-rendering, bad input answered clearly."""

from __future__ import annotations

import datetime as dt
import json
import sys

import pytest

from imc_conformance.cli import main

P1 = "imc/LblRange/crc/header-timestamp/le"  # fails with pyimclsts, which checks no CRC: erratum P1
PASSING = "imc/LblRange/minimal"


def run(*args, adapter="imcpy"):
    return main(["run", "--adapter", adapter, "--no-progress", *args])


def failing(*args):
    """A run through pyimclsts, which fails documented cases (imcpy fails none)."""
    return run(*args, adapter="pyimclsts")


def lblrange_cases() -> int:
    from imc_conformance.suites.imc.paths import imc_data
    return len(json.loads(imc_data("cases", "200-LblRange.json").read_text())["cases"])


def test_passing_selection_exits_0(capsys):
    assert run("--message", "LblRange") == 0
    out = capsys.readouterr().out
    assert "LblRange" in out and f"{lblrange_cases()} cases" in out


def test_a_failure_exits_1_and_names_the_erratum(capsys):
    assert failing("--id", P1) == 1
    out = capsys.readouterr().out
    assert f"FAIL {P1}" in out and "erratum P1" in out


def test_usage_and_adapter_errors_exit_2(capsys, tmp_path):
    assert main(["run", "--adapter", "no_such_module:adapter", "--no-progress"]) == 2
    assert "cannot load adapter 'no_such_module:adapter'" in capsys.readouterr().err
    assert run("--message", "NoSuchMessage") == 2
    assert "unknown message(s): NoSuchMessage" in capsys.readouterr().err
    assert run("--id", "imc/nothing/*") == 2
    assert main(["run", "--adapter-cmd", str(tmp_path / "missing-program"), "--no-progress"]) == 2
    assert "missing-program" in capsys.readouterr().err


def waivers(tmp_path, *entries):
    path = tmp_path / "waivers.json"
    path.write_text(json.dumps({"waivers": list(entries)}))
    return str(path)


def test_a_waived_failure_is_waived_and_exits_0(tmp_path, capsys):
    path = waivers(tmp_path, {"id": P1, "reason": "pyimclsts checks no CRC (P1)"})
    out = tmp_path / "result.json"
    assert failing("--id", P1, "--waivers", path, "--json", str(out)) == 0
    case = json.loads(out.read_text())["messages"][0]["cases"][0]
    assert case["verdict"] == "WAIVED" and case["waiver"] == "pyimclsts checks no CRC (P1)"


def test_a_waiver_on_a_passing_case_is_stale_and_exits_1(tmp_path, capsys):
    path = waivers(tmp_path, {"id": PASSING, "reason": "was broken once"})
    assert run("--id", PASSING, "--waivers", path) == 1
    assert "WAIVER_STALE imc/LblRange/minimal" in capsys.readouterr().out


def test_a_waiver_for_an_unknown_case_is_an_error(tmp_path, capsys):
    path = waivers(tmp_path, {"id": "imc/LblRange/no-such-case", "reason": "typo"})
    assert run("--id", PASSING, "--waivers", path) == 2
    assert "$.waivers[0]: no case has the id 'imc/LblRange/no-such-case'" in capsys.readouterr().err


def test_an_expired_waiver_no_longer_applies(tmp_path, capsys):
    yesterday = (dt.date.today() - dt.timedelta(days=1)).isoformat()
    path = waivers(tmp_path, {"id": P1, "reason": "temporary", "expires": yesterday})
    assert failing("--id", P1, "--waivers", path) == 1
    assert f"expired on {yesterday}" in capsys.readouterr().out


def test_write_waivers_then_adopt_them(tmp_path, capsys):
    path, result = tmp_path / "start.json", tmp_path / "r.json"
    assert failing("--id", "imc/LblRange/crc/*", "--write-waivers", str(path), "--json", str(result)) == 1
    written = json.loads(path.read_text())["waivers"]
    cases = json.loads(result.read_text())["messages"][0]["cases"]
    assert written and {w["id"] for w in written} == {c["id"] for c in cases if c["verdict"] == "FAIL"}
    assert failing("--id", "imc/LblRange/crc/*", "--waivers", str(path)) == 0


ADOPTED = ("--message", "Heartbeat", "--message", "HistoricData")  # pyimclsts fails both by several causes


def test_adopting_by_cause_takes_one_waiver_per_cause_and_exits_0(tmp_path, capsys):
    path, result = tmp_path / "causes.json", tmp_path / "r.json"
    assert failing(*ADOPTED, "--write-waivers", str(path), "--by", "cause", "--json", str(result)) == 1
    written = json.loads(path.read_text())["waivers"]
    causes = json.loads(result.read_text())["causes"]
    assert [w["cause"] for w in written] == [c["key"] for c in causes] and len(written) >= 5
    assert all(w["reason"].startswith(c["title"]) for w, c in zip(written, causes))
    assert failing(*ADOPTED, "--waivers", str(path), "--json", str(result)) == 0
    verdicts = {c["verdict"] for m in json.loads(result.read_text())["messages"] for c in m["cases"]}
    assert "WAIVED" in verdicts and "FAIL" not in verdicts


@pytest.mark.parametrize("entry", [{"glob": "imc/LblRange/crc/*"}, {"rule": "crc"}, {"cause": "accepts/rule:crc"}])
def test_a_glob_a_rule_or_a_cause_waives_the_failures_it_names(entry, tmp_path, capsys):
    path, result = waivers(tmp_path, {**entry, "reason": "pyimclsts checks no CRC (P1)"}), tmp_path / "r.json"
    assert failing("--id", "imc/LblRange/crc/*", "--id", PASSING, "--waivers", path, "--json", str(result)) == 0
    cases = {c["id"]: c for m in json.loads(result.read_text())["messages"] for c in m["cases"]}
    assert cases[P1]["verdict"] == "WAIVED" and cases[P1]["waiver"] == "pyimclsts checks no CRC (P1)"
    assert cases[PASSING]["verdict"] == "PASS"  # a broad waiver applies to failures only: no WAIVER_STALE here


@pytest.mark.parametrize("entry", [{"cause": "accepts/rule:crc"}, {"rule": "crc"}, {"glob": "imc/LblRange/crc/*"}])
def test_a_broad_waiver_that_waives_nothing_is_stale_and_exits_1(entry, tmp_path, capsys):
    path = waivers(tmp_path, {**entry, "reason": "fixed since"})
    assert run("--id", "imc/LblRange/crc/*", "--waivers", path) == 1  # imcpy checks the CRC
    name = next(iter(entry.items()))
    assert f"WAIVER_STALE: the waiver of {name[0]} {name[1]} names cases of this run but waives none" in \
        capsys.readouterr().out


@pytest.mark.parametrize("entry, error", [
    ({"cause": "accepts/rule:crcc"}, "'accepts/rule:crcc' is not a cause key of this corpus"),
    ({"rule": "crcc"}, "the suite has no rule 'crcc'"), ({"glob": "imc/Nothing/*"}, "no case id matches the glob"),
    ({"rule": "crc", "cause": "accepts/rule:crc"}, "$.waivers[0]"),
])
def test_a_waiver_naming_nothing_of_the_corpus_is_an_error(entry, error, tmp_path, capsys):
    path = waivers(tmp_path, {**entry, "reason": "typo"})
    assert run("--id", PASSING, "--waivers", path) == 2
    assert error in capsys.readouterr().err
    assert run("--id", PASSING, "--by", "cause") == 2  # --by without --write-waivers
    assert "give --write-waivers FILE too" in capsys.readouterr().err


def test_reports_are_written_and_re_rendered(tmp_path, capsys):
    files = {fmt: tmp_path / f"r.{fmt}" for fmt in ("json", "junit", "markdown", "html")}
    assert failing("--id", "imc/LblRange/crc/*", *(a for fmt, p in files.items() for a in (f"--{fmt}", str(p)))) == 1
    assert all(p.stat().st_size > 500 for p in files.values())
    again = tmp_path / "again.html"
    assert main(["report", str(files["json"]), "--html", str(again)]) == 1
    assert again.read_text() == files["html"].read_text()
    assert main(["report", str(files["markdown"])]) == 2  # not a JSON result


def test_strict_turns_non_strict_into_failure(tmp_path, capsys):
    adapter = tmp_path / "blames_crc.py"
    adapter.write_text(
        "from imc_conformance.suites.imc import codec\n"
        "from imc_conformance.adapter_api import Rejected\n"
        "from imc_conformance.suites.imc.definitions import load_definitions\n"
        "D = load_definitions()\n"
        "class A:\n"
        "    def hello(self): return {'implementation': 'blames-crc', 'suites': ['imc'], 'byte_orders': ['le', 'be']}\n"
        "    def encode(self, s, m, o): return codec.encode(D, m, o)\n"
        "    def decode(self, s, f):\n"
        "        try: return codec.decode(D, f)\n"
        "        except codec.FrameError as e: raise Rejected(e.detail, 'crc')\n"
        "adapter = A()\n")
    args = ["run", "--adapter", f"{adapter}:adapter", "--no-progress", "--id", "imc/LblRange/sync/*"]
    assert main(args) == 0
    assert main([*args, "--strict"]) == 1
    assert "NON_STRICT imc/LblRange/sync/zero/le" in capsys.readouterr().out


def test_list_prints_ids_expectations_and_clauses(capsys):
    assert main(["list", "--message", "LblRange", "--tag", "invalid"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines and all(line.split("\t")[1] == "invalid" for line in lines)
    assert "imc/LblRange/crc/footer-first-byte/le\tinvalid\timc-xml#footer.crc16" in lines


@pytest.mark.parametrize("edition,expected", [("imc-5.4.30", "valid"), ("imc-5.4.11", "acceptable")])
def test_editions_change_expectations(edition, expected, capsys):
    assert main(["list", "--edition", edition, "--id", "imc/AcousticStatus/enum/status/DELIVERED-4"]) == 0
    assert capsys.readouterr().out.split("\t")[1] == expected


@pytest.mark.parametrize("mangle,message", [
    (lambda doc: doc["cases"][0].update(expect="maybe"), "$.cases[0].expect: 'maybe' is not valid"),
    (lambda doc: doc["cases"][0]["frames"].update(le="54f"), "$.cases[0].frames.le: '54f' does not match"),
    (lambda doc: doc["cases"][-1].pop("rule"), "]: 'rule' is a required property"),
    (lambda doc: doc.update(cases={}), "$.cases: {} is not of type 'array'"),
])
def test_a_malformed_vector_file_names_the_file_and_json_path(tmp_path, capsys, mangle, message):
    from imc_conformance.suites.imc.paths import imc_data
    doc = json.loads(imc_data("cases", "200-LblRange.json").read_text())
    mangle(doc)
    (tmp_path / "200-LblRange.json").write_text(json.dumps(doc))
    assert run("--vectors", str(tmp_path)) == 2
    err = capsys.readouterr().err
    assert "200-LblRange.json" in err and message in err


def test_a_vector_file_that_is_not_json_says_where(tmp_path, capsys):
    (tmp_path / "bad.json").write_text('{"cases": [\n  {"id": }\n]}')
    assert main(["list", "--vectors", str(tmp_path)]) == 2
    assert "bad.json: not JSON (line 2, column 10)" in capsys.readouterr().err


def test_a_custom_vector_directory_runs(tmp_path, capsys):
    from imc_conformance.suites.imc.paths import imc_data
    (tmp_path / "200-LblRange.json").write_text(imc_data("cases", "200-LblRange.json").read_text())
    assert run("--vectors", str(tmp_path)) == 0
    assert f"{lblrange_cases()} cases" in capsys.readouterr().out


@pytest.mark.parametrize("name, module", [("rosbags", "numpy"), ("genpy", "yaml")])
def test_a_built_in_adapter_without_its_extra_names_the_extra(name, module, monkeypatch, capsys):
    """A wheel installed without the ros extra: the module the adapter needs is missing (simulated: the import of it
    fails), and the one line says what to install, exit 2."""
    monkeypatch.setitem(sys.modules, module, None)  # `import numpy` now raises ModuleNotFoundError
    monkeypatch.delitem(sys.modules, f"imc_conformance.adapters.{name}_adapter", raising=False)
    code = main(["run", "--suite", "ros_acomms", "--adapter", name, "--message", "CST"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    assert f"adapter '{name}' needs the 'ros' extra, installed with the suite: pip install '.[ros]' in its checkout" \
        in err[0], err
