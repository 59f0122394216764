"""The fuzzer: strategies from the definitions give valid cases for every message and type, each frame mutation
breaks what it aims at, a search is reproducible and shrinks what it finds, findings are classified and labelled by
errata, a crashing implementation is a finding, promotion makes a permanent vector, and the seeded bugs the corpus
misses are caught within the CI budget."""

from __future__ import annotations

import json
import sys
import textwrap

import pytest
from hypothesis import HealthCheck, given, settings

from imc_conformance.cli import main
from imc_conformance.core.cases import Case
from imc_conformance.files import open_corpus, schema_error
from imc_conformance.fuzz import promote
from imc_conformance.suites.imc.corpus.samples import ORDINARY_HEADER
from imc_conformance.fuzz.engine import Search
from imc_conformance.fuzz.mutation import score
from imc_conformance.paths import VECTORS
from imc_conformance.sessions.library import LibrarySession
from imc_conformance.suites.imc import codec, mutants
from imc_conformance.suites.ros_acomms import mutants as ros_mutants

EDITION = "imc-5.4.30"
QUICK = settings(max_examples=15, deadline=None, derandomize=True, database=None,
                 suppress_health_check=list(HealthCheck))


@pytest.fixture(scope="module")
def imc():
    suite, cases = open_corpus("imc")
    return suite, cases, suite.fuzz_source(EDITION, cases)


@pytest.fixture(scope="module")
def ros_source(ros):
    suite, cases = ros
    return suite.fuzz_source("seed", cases)


def wrapped(suite, case: dict) -> dict:
    """A case file holding one case, as the generator writes them (for the schema check)."""
    if suite.name == "imc":
        mdef = suite.defs[case["id"].split("/")[1]]
        return {"format": 1, "suite": "imc", "editions": list(suite.editions), "cases": [case],
                "message": {"abbrev": mdef.abbrev, "id": mdef.id, "name": mdef.name, "clause": mdef.clause,
                            "definition": mdef.hash}}
    t = suite.defs.by_full[case["type"]]
    return {"format": 1, "suite": "ros_acomms", "editions": list(suite.editions), "cases": [case],
            "message": {"name": t.name, "type": t.full, "kind": t.kind, "clause": t.clause}}


def assert_valid_case(suite, case: dict) -> None:
    assert schema_error(suite.schema("vector"), wrapped(suite, case), case["id"]) is None
    assert suite.case_problem("vector", case) is None


# ---------------------------------------------------------------- strategies from the definitions

@pytest.mark.parametrize("group", [m.abbrev for m in open_corpus("imc", None, frozenset())[0].defs.suite_messages])
def test_every_imc_message_generates_valid_cases(imc, group):
    suite, _, source = imc

    @QUICK
    @given(source.inputs(group, "message"))
    def check(drawn):
        case = source.case(group, "message", drawn)
        if case is None:  # too large to frame: refused by the reference, never a case
            with pytest.raises(codec.EncodeError):
                codec.encode(suite.defs, drawn, "le")
            return
        # a zero timestamp may be stamped on encode (class zero-timestamp): such a message is acceptable, only for that
        zero = case["message"]["header"]["timestamp"] == 0
        assert case["expect"] == {EDITION: "acceptable" if zero else "valid"} and case["id"].startswith(f"imc/{group}/fuzz/")
        assert case.get("class") == ("zero-timestamp" if zero else None)
        for order, frame in case["frames"].items():
            assert codec.decode(suite.defs, bytes.fromhex(frame)) == case["message"]
        assert_valid_case(suite, case)
    check()


@pytest.mark.parametrize("group", [t.name for t in open_corpus("ros_acomms", None, frozenset())[0].defs.suite_types])
def test_every_ros_type_generates_valid_cases(ros, ros_source, group):
    suite, _ = ros

    @QUICK
    @given(ros_source.inputs(group, "message"))
    def check(drawn):
        case = ros_source.case(group, "message", drawn)
        assert case is not None and case["expect"] == {"seed": "valid"}
        assert_valid_case(suite, case)
    check()


@pytest.mark.parametrize("which", ["imc", "ros"])
def test_mutated_frames_are_valid_cases_with_the_reference_verdict(imc, ros, ros_source, which):
    suite, source = (imc[0], imc[2]) if which == "imc" else (ros[0], ros_source)
    group = source.groups[3]

    @QUICK
    @given(source.inputs(group, "frame"))
    def check(drawn):
        case = source.case(group, "frame", drawn)
        if case is None:
            return
        assert f"mutation:{drawn['mutation']}" in case["tags"]
        (expect,) = case["expect"].values()
        assert expect in ("valid", "invalid", "acceptable")
        assert (expect == "invalid") == ("rule" in case)
        assert_valid_case(suite, case)
    check()


@pytest.mark.parametrize("mutation, rule", [("crc", "crc"), ("sync", "sync"), ("size-past-data", "size-exceeds-data"),
                                            ("prefix-past-data", None)])
def test_each_mutation_breaks_what_it_aims_at(imc, mutation, rule):
    suite, _, source = imc
    frame = codec.encode(suite.defs, {"abbrev": "AcousticSystems", "header": {}, "fields": {"list": "lauv-1"}}, "be")
    case = source.frame_case("AcousticSystems", "be", source.mutate("AcousticSystems", frame, "be", mutation, 5, 3),
                             mutation)
    assert case["expect"] == {EDITION: "invalid"}
    assert case["rule"] == (rule or "length-overrun")


def test_trailing_bytes_are_an_acceptable_case(imc):
    suite, _, source = imc
    frame = codec.encode(suite.defs, {"abbrev": "LblRange", "header": {}, "fields": {"id": 1, "range": 2.5}}, "le")
    case = source.frame_case("LblRange", "le", source.mutate("LblRange", frame, "le", "extend", 7, 2), "extend")
    assert case["expect"] == {EDITION: "acceptable"} and "trailing-bytes" in case["tags"]


# ---------------------------------------------------------------- the search

def search(imc, adapter, groups, seed=5, budget=60, props=("message", "frame")):
    suite, _, source = imc
    return Search(suite, source, {adapter.name: LibrarySession(adapter, adapter.name)}, EDITION, seed=seed,
                  budget=budget).run(groups, props)


def test_a_value_conditioned_bug_is_found_and_shrunk(imc, defs):
    """The issue's own example: a decoder that drops the last element of a five-element message-list passes the
    whole corpus; the search finds it, shrunk to five default elements."""
    tally = search(imc, mutants.DropsFifthListElement(defs), ["LblConfig"], seed=1, props=("message",))
    (finding,) = tally.findings
    beacons = finding.case["message"]["fields"]["beacons"]
    assert len(beacons) == 5
    assert finding.classification == "drops-fifth-list-element deviates from the reference"
    assert finding.unexplained == ["drops-fifth-list-element"]


def test_the_same_seed_gives_the_same_findings(imc, defs):
    runs = [search(imc, mutants.DropsFifthListElement(defs), ["LblConfig"], seed=s) for s in (1, 1)]
    dumps = [json.dumps([(f.case, f.classification) for f in t.findings], sort_keys=True) for t in runs]
    assert runs[0].findings and dumps[0] == dumps[1]
    assert runs[0].judged == runs[1].judged


def test_a_correct_implementation_has_no_finding(imc, defs):
    tally = search(imc, mutants.Reference(defs), ["Announce", "HistoricData"], budget=40)
    assert tally.findings == [] and all(30 <= n <= 40 for n in tally.judged.values())  # too large to frame: not judged


def test_several_implementations_are_classified(imc, defs):
    suite, _, source = imc
    sessions = {m.name: LibrarySession(m, m.name) for m in (mutants.Reference(defs), mutants.TrimsTrailingSpaces(defs))}
    tally = Search(suite, source, sessions, EDITION, seed=0, budget=80).run(["SmsRx"], ("message",))
    assert [f.classification for f in tally.findings] == ["trims-trailing-spaces deviates; reference matches the reference"]


def test_a_crash_is_a_finding_with_the_input_that_caused_it(tmp_path, capsys):
    """A library adapter dies (SIGSEGV) on any frame over 30 bytes: run in its worker process, that is a CRASH
    finding, shrunk, and the fuzzer goes on to report it."""
    program = tmp_path / "segfaulting.py"
    program.write_text(textwrap.dedent("""
        import os, signal
        from imc_conformance.suites import load_suite
        from imc_conformance.suites.imc.mutants import Reference

        class Segfaults(Reference):
            name = "segfaults"
            def decode_frame(self, frame):
                if len(frame) > 30:
                    os.kill(os.getpid(), signal.SIGSEGV)
                return super().decode_frame(frame)

        adapter = Segfaults(load_suite("imc").defs)
    """))
    report = tmp_path / "fuzz.json"
    code = main(["fuzz", "--adapter", f"{program}:adapter", "--message", "AcousticSystems", "--property", "message",
                 "--budget", "30", "--json", str(report)])
    assert code == 1
    doc = json.loads(report.read_text())
    (case,) = [c for m in doc["messages"] for c in m["cases"]]
    assert case["verdict"] == "CRASH"
    crashed = [c for c in case["checks"] if c["verdict"] == "CRASH"]
    assert crashed and all(len(bytes.fromhex(c["expected"])) > 30 for c in crashed)


def test_a_library_adapter_s_non_finite_floats_cross_the_worker_as_in_process(tmp_path):
    """A library adapter may answer NaN and the infinities as Python floats (adapters/README.md): in its worker
    process they become the decoded form's words, so the verdicts are those of the adapter run in-process."""
    from harness import verdicts

    from imc_conformance.sessions.subprocess import SubprocessSession

    program = tmp_path / "floats.py"
    program.write_text(textwrap.dedent("""
        from imc_conformance.suites import load_suite
        from imc_conformance.suites.imc.mutants import Reference

        WORDS = {"nan": float("nan"), "inf": float("inf"), "-inf": float("-inf")}

        class PythonFloats(Reference):
            name = "python-floats"
            def decode(self, suite, frame, **params):
                message = super().decode(suite, frame, **params)
                message["fields"] = {k: WORDS.get(v, v) if isinstance(v, str) else v
                                     for k, v in message["fields"].items()}
                return message

        adapter = PythonFloats(load_suite("imc").defs)
    """))
    suite, cases = open_corpus("imc")
    chosen = [c for c in cases if c.group in ("LblRange", "VSWR") and c.kind == "vector"]
    worker = SubprocessSession([sys.executable, "-m", "imc_conformance.sessions.worker", "--suite", "imc",
                                f"{program}:adapter"],
                               name="worker", encoding_param="byte_order", hello_timeout=60)
    try:
        isolated = {cid: v for cid, (v, _) in verdicts(worker, chosen, EDITION).items()}
    finally:
        worker.close()
    namespace = {}
    exec(compile(program.read_text(), str(program), "exec"), namespace)
    in_process = {cid: v for cid, (v, _) in verdicts(namespace["adapter"], chosen, EDITION).items()}
    assert isolated == in_process
    assert any("/inf" in cid or "/nan" in cid for cid in in_process)


def test_documented_errata_label_findings_and_do_not_fail_the_run(capsys, tmp_path):
    """imcpy's Python binding quiets fp32 signalling NaNs (erratum I4): found by fuzzing, explained, exit 0."""
    report = tmp_path / "fuzz.json"
    code = main(["fuzz", "--adapter", "imcpy", "--in-process", "--message", "VSWR", "--property", "message",
                 "--seed", "1", "--budget", "60", "--json", str(report)])
    doc = json.loads(report.read_text())
    found = [c for m in doc["messages"] for c in m["cases"] if "/fuzz/" in c["id"] and c["verdict"] != "PASS"]
    assert found and all(c["errata"] == ["I4"] for c in found)
    assert code == 0


def test_promotion_end_to_end(tmp_path, capsys, defs):
    """Found, shrunk, promoted, then caught by a plain run: the promoted file is a source the generator reads."""
    program = tmp_path / "mutant.py"
    program.write_text("from imc_conformance.suites import load_suite\n"
                       "from imc_conformance.suites.imc.mutants import DropsFifthListElement\n"
                       "adapter = DropsFifthListElement(load_suite('imc').defs)\n")
    promoted = tmp_path / "vectors" / "promoted.json"
    args = ["fuzz", "--adapter", f"{program}:adapter", "--in-process", "--message", "LblConfig", "--property",
            "message", "--seed", "1", "--budget", "60", "--promote", str(promoted)]
    assert main(args) == 1
    assert main(args) == 1  # promoted twice: added once
    records = promote.read(promoted, "imc")
    assert len(records) == 1 and records[0]["provenance"]["seed"] == 1
    # reduced to the one property it deviates on: the header hypothesis shrank to zeros is the ordinary one again
    assert records[0]["input"]["message"]["header"] == ORDINARY_HEADER
    assert schema_error(VECTORS / "schema" / "promoted.schema.json", json.loads(promoted.read_text()), "p") is None
    suite = open_corpus("imc")[0]
    built = promote.promoted_cases(records, {e: suite.fuzz_source(e) for e in suite.editions})
    (case,) = built["LblConfig"]
    assert case["id"] == records[0]["id"] and case["provenance"] == records[0]["provenance"]
    folder = tmp_path / "corpus"
    (folder / "cases").mkdir(parents=True)
    (folder / "cases" / "203-LblConfig.json").write_text(json.dumps(wrapped(suite, case)))
    assert main(["run", "--vectors", str(folder), "--adapter", f"{program}:adapter", "--no-progress"]) == 1
    assert main(["run", "--vectors", str(folder), "--adapter", "imcpy", "--no-progress"]) == 0


# ---------------------------------------------------------------- the suite's power

NEW_IMC = {m.name: m for m in mutants.NEW}
NEW_ROS = {m.name: m for m in ros_mutants.NEW}


@pytest.mark.parametrize("name", sorted(NEW_IMC))
def test_every_new_imc_mutant_is_caught(imc, defs, name):
    suite, cases, source = imc
    mutant = next(m for m in suite.mutants(EDITION) if m.name == name)
    outcome = score(suite, mutant, [c for c in cases if c.kind == "vector"], EDITION, source, seed=0, budget=40)
    assert outcome.caught_by is not None, f"{name} survived the corpus and {outcome.judged} examples"


@pytest.mark.parametrize("name", sorted(NEW_ROS))
def test_every_new_ros_mutant_is_caught(ros, ros_source, name):
    suite, cases = ros
    mutant = next(m for m in suite.mutants("seed") if m.name == name)
    outcome = score(suite, mutant, [c for c in cases if c.kind == "vector"], "seed", ros_source, seed=0, budget=40)
    assert outcome.caught_by is not None, f"{name} survived the corpus and {outcome.judged} examples"


def test_fuzz_only_catches_are_what_the_corpus_misses(imc):
    """The value-conditioned bugs pass every corpus vector: only generated inputs catch them."""
    suite, cases, source = imc
    chosen = {"fp64-wrong-1e3-1e5", "trims-trailing-spaces"}
    for mutant in (m for m in suite.mutants(EDITION) if m.name in chosen):
        outcome = score(suite, mutant, [c for c in cases if c.kind == "vector"], EDITION, source, seed=0, budget=40)
        assert outcome.how == "fuzz" and outcome.corpus_cases == 0


def test_mutants_command_reports_equivalent_survivors(capsys):
    code = main(["mutants", "--mutant", "refuses-trailing-bytes", "--mutant", "crc-ccitt", "--budget", "5"])
    out = capsys.readouterr().out
    assert code == 0
    assert "EQUIVALENT" in out and "CAUGHT" in out and "score 1/1" in out


# ---------------------------------------------------------------- command line

@pytest.mark.parametrize("args, message", [
    (["--budget", "0"], "--budget 0"),
    (["--message", "Nope"], "unknown message"),
    (["--adapter", "imcpy", "--adapter", "imcpy"], "named twice"),
    (["--adapter", "no.such.module:x"], "cannot load adapter"),
])
def test_fuzz_usage_errors_are_one_line(capsys, args, message):
    assert main(["fuzz", *args]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1


def test_promote_refuses_a_file_of_another_suite(tmp_path, capsys):
    other = tmp_path / "promoted.json"
    other.write_text(json.dumps({"format": 1, "suite": "ros_acomms", "promoted": []}))
    assert main(["fuzz", "--adapter", "imcpy", "--in-process", "--message", "Heartbeat", "--budget", "3",
                 "--promote", str(other)]) == 2
    assert "not a promoted-findings file of the suite 'imc'" in capsys.readouterr().err


def test_findings_do_not_depend_on_what_the_process_has_loaded(tmp_path, capsys):
    """The same seed and budget give the same findings in a fresh process (the wheel's view: no test modules, no
    editable source) as in this one, which has loaded the whole test suite."""
    import subprocess
    import sys

    program = tmp_path / "mutant.py"
    program.write_text("from imc_conformance.suites import load_suite\n"
                       "from imc_conformance.suites.imc.mutants import DropsFifthListElement\n"
                       "adapter = DropsFifthListElement(load_suite('imc').defs)\n")
    args = ["fuzz", "--adapter", f"{program}:adapter", "--in-process", "--message", "LblConfig", "--seed", "3",
            "--budget", "40"]
    here, there = tmp_path / "here.json", tmp_path / "there.json"
    main([*args, "--json", str(here)])
    subprocess.run([sys.executable, "-m", "imc_conformance.cli", *args, "--json", str(there)], cwd=tmp_path,
                   capture_output=True, timeout=300)
    cases = [[c for m in json.loads(p.read_text())["messages"] for c in m["cases"]] for p in (here, there)]
    assert cases[0] == cases[1] and any("/fuzz/" in c["id"] and c["verdict"] == "FAIL" for c in cases[0])


@pytest.mark.parametrize("suite_name, adapter, erratum", [("imc", "imcpy", "I4"), ("imc", "pyimclsts", "P6"),
                                                          ("ros_acomms", "rosbags", "R2"), ("ros_acomms", "genpy", "G3")])
def test_the_errata_the_fuzzer_found_are_still_observed(suite_name, adapter, erratum):
    """A signalling NaN in a 32-bit float arrives quiet in all four Python implementations: a generated case holding
    one fails with each, labelled with its erratum."""
    from imc_conformance.commands.adapters import load_library_adapter
    from imc_conformance.core.runner import run_cases

    suite, cases = open_corpus(suite_name)
    edition = suite.editions[0]
    source = suite.fuzz_source(edition, cases)
    if suite_name == "imc":
        group, message = "LblRange", {"abbrev": "LblRange", "header": {}, "fields": {"id": 1, "range": "nan:7f800001"}}
    else:
        group = "TTA"
        message = {"type": "ros_acomms_msgs/TTA", "fields": {
            "header": {"seq": 0, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": ""}, "time_of_ping": "nan:7f800001",
            "a_flag": 0.0, "b_flag": 0.0, "c_flag": 0.0, "d_flag": 0.0}}
    case = source.case(group, "message", message)
    session = LibrarySession(load_library_adapter(adapter, suite), adapter)
    (result,) = run_cases(session, suite, [Case(case["id"], group, "vector", case)], edition=edition,
                          adapter=adapter).cases
    assert result.verdict.value == "FAIL" and result.errata == [erratum]


def test_live_fuzzing_names_the_generated_frame_that_silences_a_node(suite, cases):
    """fuzz --target: mutated requests take the corpus's place in the robustness phase. A node that dies on any RAW
    acoustic request is found, and bisected to a generated frame (on virtual time: the harness of the live tests)."""
    import random

    from live_harness import run_virtual

    from imc_conformance.fuzz.engine import mutated_cases

    source = suite.fuzz_source(EDITION, cases)
    rng = random.Random("live")
    generated = tuple(Case(i, i.split("/")[1], "vector", c)
                      for i, (c, _) in mutated_cases(source, "AcousticRequest", rng, 300).items())
    from live_harness import EVERYTHING

    result, link = run_virtual(suite, cases, kinds=("robustness",), restartable=True, broken="dies-after-raw",
                               options=dict(EVERYTHING, corpus=generated))
    failed = {c.id: c for c in result.cases if c.verdict.value == "FAIL"}
    assert "imc/AcousticRequest/robustness/still-served" in failed
    assert "bisected: the frame imc/AcousticRequest/fuzz/" in failed["imc/AcousticRequest/robustness/still-served"].detail
    assert link.restarts >= 1


def test_live_fuzzing_needs_effects_allowed(capsys):
    assert main(["fuzz", "--target", "udp://127.0.0.1:9"]) == 2
    assert "--allow-effects" in capsys.readouterr().err


def test_a_duration_ends_the_search_and_says_so(tmp_path, capsys):
    report = tmp_path / "r.json"
    assert main(["fuzz", "--adapter", "imcpy", "--in-process", "--budget", "1000000", "--duration", "1",
                 "--json", str(report)]) == 0
    notes = json.loads(report.read_text())["notes"]
    assert any("stopped early: the duration was spent" in n for n in notes)
    assert any("bounded by --duration" in n for n in notes)


def test_a_fuzzing_result_is_a_result_document_that_report_and_matrix_read(tmp_path, capsys):
    report, html = tmp_path / "fuzz.json", tmp_path / "fuzz.html"
    main(["fuzz", "--adapter", "imcpy", "--adapter", "pyimclsts", "--message", "LblRange", "--budget", "10",
          "--json", str(report)])
    assert main(["report", str(report), "--html", str(html)]) in (0, 1)
    assert main(["matrix", str(report), "--markdown", str(tmp_path / "m.md")]) == 0
    assert "(fuzzing)" in (tmp_path / "m.md").read_text()


def test_a_sweep_with_findings_does_not_also_say_everything_agreed(tmp_path, capsys):
    report = tmp_path / "sweep.json"
    main(["fuzz", "--adapter", "pyimclsts", "--in-process", "--message", "LblRange", "--property", "message",
          "--budget", "1", "--sweep", "200", "--json", str(report)])
    cases = [c for m in json.loads(report.read_text())["messages"] for c in m["cases"]]
    assert any(c["verdict"] == "FAIL" for c in cases)  # pyimclsts checks no CRC (P1): the sweep finds it
    assert not any(c["id"] == "imc/LblRange/fuzz/sweep" for c in cases)


@pytest.mark.parametrize("content, message", [
    ({"format": 1, "suite": "imc", "promoted": [1]}, "$.promoted[0]: 1 is not of type 'object'"),
    ({"format": 1, "suite": "imc", "promoted": [{"id": "imc/LblRange/fuzz/0"}]}, "$.promoted[0]"),
])
def test_promote_refuses_a_file_that_breaks_its_schema_in_one_line(tmp_path, capsys, content, message):
    bad = tmp_path / "promoted.json"
    bad.write_text(json.dumps(content))
    assert main(["fuzz", "--adapter", "imcpy", "--in-process", "--message", "Heartbeat", "--budget", "3",
                 "--promote", str(bad)]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1


def test_a_database_is_refused_with_the_reason_and_a_suite_without_probes_is_a_usage_error(tmp_path, capsys):
    """--database was a silent no-op (a seeded search keeps no example database): it is refused, saying why, and
    nothing is written where it points."""
    assert main(["fuzz", "--adapter", "imcpy", "--in-process", "--message", "Heartbeat", "--budget", "3",
                 "--database", str(tmp_path / "db")]) == 2
    err = capsys.readouterr().err
    assert "hypothesis keeps no example database for a seeded search" in err and "--promote" in err
    assert err.count("\n") == 1 and not (tmp_path / "db").exists()
    assert main(["fuzz", "--suite", "ros_acomms", "--target", "udp://127.0.0.1:9", "--allow-effects"]) == 2
    assert "cannot be fuzzed live" in capsys.readouterr().err
