"""Hostile and mistaken input gets a clear answer: usage errors exit 2 with one line, a hostile adapter can
neither fool the gate nor the terminal, an interrupted run keeps what it gathered, no process outlives a run.

Most tests drive the command line in-process; the hostile adapter (``tests/hostile_adapter.py``) is one
program with a mode per misbehaviour, misbehaving on the trigger frame only.
"""

from __future__ import annotations

import copy
import json
import os
import shlex
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from harness import alive
from imc_conformance.cli import main
from imc_conformance.suites.imc.paths import imc_data

HERE = Path(__file__).resolve().parent
HOSTILE = HERE / "hostile_adapter.py"
TRIGGER = "imc/LblRange/realistic/crosscheck"
LBLRANGE = json.loads(imc_data("cases", "200-LblRange.json").read_text(encoding="utf-8"))
TRIGGER_FRAME = next(c for c in LBLRANGE["cases"] if c["id"] == TRIGGER)["frames"]["le"]
CONTROL = ("\x1b", "\x00", "\r", "\x07", "\x9b")


def frame_of(case_id: str, order: str = "le") -> str:
    return next(c for c in LBLRANGE["cases"] if c["id"] == case_id)["frames"][order]


def hostile_cmd(mode: str, trigger: str = TRIGGER_FRAME) -> str:
    return shlex.join([sys.executable, str(HOSTILE), mode, trigger])


@pytest.fixture
def hostile(tmp_path, monkeypatch):
    """Run the CLI against a hostile mode; returns (exit code, JSON result or None, stdout, stderr)."""
    monkeypatch.setenv("HOSTILE_PIDS", str(tmp_path / "pids"))
    monkeypatch.setenv("HOSTILE_STATE", str(tmp_path))

    def run(mode: str, *args: str, capsys=None, selection=("--message", "LblRange"), reports=("json",)):
        out = {fmt: tmp_path / f"result.{fmt}" for fmt in reports}
        report_args = [a for fmt, path in out.items() for a in (f"--{fmt}", str(path))]
        code = main(["run", "--adapter-cmd", hostile_cmd(mode), "--no-progress", "--timeout", "3",
                     *selection, *report_args, *args])
        doc = json.loads(out["json"].read_text()) if "json" in out and out["json"].exists() else None
        return code, doc, out
    return run


def verdicts(doc: dict) -> dict[str, str]:
    return {c["id"]: c["verdict"] for m in doc["messages"] for c in m["cases"]}


def case(doc: dict, case_id: str) -> dict:
    return next(c for m in doc["messages"] for c in m["cases"] if c["id"] == case_id)


def survivors(tmp_path: Path) -> list[int]:
    """Processes the hostile adapter started that are still alive (a short bound for the kernel to reap them)."""
    pids_file = tmp_path / "pids"
    pids = [int(p) for p in pids_file.read_text().split()] if pids_file.exists() else []
    for _ in range(50):
        left = [p for p in pids if alive(p)]
        if not left:
            return []
        time.sleep(0.1)
    return left


def one_line_error(err: str, *fragments: str) -> None:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("imc-conformance: "), err
    assert "Traceback" not in err
    for fragment in fragments:
        assert fragment in lines[0], lines[0]


# ---------------------------------------------------------------- 1. the adapter to run is never guessed

@pytest.mark.parametrize("args, fragment", [
    (["--adapter-cmd", ""], "--adapter-cmd is empty"),
    (["--adapter-cmd", "   "], "--adapter-cmd is empty"),
    (["--adapter-cmd", "python3 'unbalanced"], "--adapter-cmd cannot be split: No closing quotation"),
    (["--adapter", "imcpy", "--adapter-cmd", "python3 x.py"], "give one of --adapter, --adapter-cmd, not several"),
])
def test_an_ambiguous_or_empty_adapter_is_a_usage_error(args, fragment, capsys):
    assert main(["run", *args, "--no-progress", "--id", "imc/LblRange/minimal"]) == 2
    one_line_error(capsys.readouterr().err, fragment)


# ---------------------------------------------------------------- 2. every value of every vector is checked

@pytest.mark.parametrize("mangle, where", [
    (lambda c: c["message"]["fields"].update(range="abc"), "$.cases[0].message.fields.range: "),
    (lambda c: c["message"]["fields"].update(range=None), "$.cases[0].message.fields.range: "),
    (lambda c: c["message"].update(header="x"), "$.cases[0].message.header: "),
    (lambda c: c["message"].update(fields={}), "$.cases[0].message.fields: "),
    (lambda c: c["message"]["fields"].update(id=1.5), "$.cases[0].message.fields.id: "),
    (lambda c: c["message"]["fields"].update(id=99999), "$.cases[0].message.fields.id: "),
    (lambda c: c["message"].update(abbrev="NoSuchMessage"), "$.cases[0].message.abbrev: "),
    (lambda c: c.update(tags=[1]), "$.cases[0].tags[0]: "),
    (lambda c: c["message"]["header"].update(src=-1), "$.cases[0].message.header.src: "),
    (lambda c: c["message"]["fields"].update(extra=1), "$.cases[0].message.fields: "),
])
def test_a_malformed_value_in_a_vector_is_a_corpus_error(tmp_path, capsys, mangle, where):
    doc = copy.deepcopy(LBLRANGE)
    assert doc["cases"][0]["id"] == "imc/LblRange/minimal"
    mangle(doc["cases"][0])
    (tmp_path / "200-LblRange.json").write_text(json.dumps(doc))
    assert main(["run", "--adapter", "imcpy", "--no-progress", "--vectors", str(tmp_path)]) == 2
    one_line_error(capsys.readouterr().err, "200-LblRange.json: " + where)


def test_the_out_of_type_enum_value_of_the_seeds_stays_loadable(capsys):
    assert main(["list", "--edition", "imc-5.4.11", "--id", "imc/AcousticStatus/enum-out-of-type/*"]) == 0
    assert "UNSUPPORTED-666" in capsys.readouterr().out


# ---------------------------------------------------------------- 3. no terminal escape reaches the terminal

@pytest.mark.parametrize("mode, code, words", [
    ("hostile-text", 1, ("hostile", "refused")),  # the hello's name, a refusal, stderr
    ("hostile-internal", 2, ("KeyError",)),  # an internal error's text
])
def test_implementation_text_cannot_drive_the_terminal(hostile, capsys, mode, code, words):
    got, doc, _ = hostile(mode)
    out, err = capsys.readouterr()
    assert got == code and doc["messages"][0]["cases"]
    assert all(word in out for word in words)
    assert not [c for c in CONTROL if c in out + err], repr(out[:500])
    assert "FORGED" not in "".join(line for line in out.splitlines() if line.startswith("FORGED"))
    assert "\\x1b" in out  # shown, not obeyed


# ---------------------------------------------------------------- 4. Ctrl-C keeps what was gathered

def test_ctrl_c_stops_cleanly_and_writes_the_reports(tmp_path):
    env = {**os.environ, "HOSTILE_PIDS": str(tmp_path / "pids"), "HOSTILE_STATE": str(tmp_path)}
    reports = {fmt: tmp_path / f"r.{fmt}" for fmt in ("json", "junit", "markdown", "html")}
    hang = "imc/LblRange/unknown-id/999/be"  # late in the run: the decode-only cases before it are all answered
    argv = [sys.executable, "-m", "imc_conformance.cli", "run", "--adapter-cmd", hostile_cmd("hang", frame_of(hang, "be")),
            "--timeout", "60", "--no-progress", "--message", "LblRange", "--tag", "invalid",
            *(a for fmt, p in reports.items() for a in (f"--{fmt}", str(p)))]
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env, text=True)
    try:
        for _ in range(600):  # the adapter marks the moment it starts hanging on the trigger frame
            if (tmp_path / "hanging").exists() or proc.poll() is not None:
                break
            time.sleep(0.1)
        assert (tmp_path / "hanging").exists()
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=60)
    finally:
        proc.kill()
    assert proc.returncode == 130, err
    assert "Traceback" not in err and "interrupted" in err
    doc = json.loads(reports["json"].read_text())
    assert doc["complete"] is False and doc["exit_code"] == 130
    done = verdicts(doc)
    assert hang not in done and "imc/LblRange/sync/first-byte/le" in done and set(done.values()) == {"PASS"}
    assert "incomplete" in reports["markdown"].read_text().lower()
    assert "incomplete" in reports["html"].read_text().lower()
    assert 'name="complete" value="false"' in reports["junit"].read_text()
    assert survivors(tmp_path) == []


# ---------------------------------------------------------------- 5. no descendant survives, exits are seen

def test_an_adapter_that_exits_while_its_child_holds_stdout_is_a_crash(hostile, tmp_path, capsys):
    code, doc, _ = hostile("fork-exit", "--timeout", "30")
    assert code == 1
    trigger = case(doc, TRIGGER)
    assert trigger["verdict"] == "CRASH" and "exited with code 7" in trigger["detail"]
    assert survivors(tmp_path) == []


def test_descendants_of_the_adapter_do_not_outlive_the_run(hostile, tmp_path, capsys):
    code, doc, _ = hostile("fork-linger")
    assert code == 0 and len((tmp_path / "pids").read_text().split()) == 2
    assert survivors(tmp_path) == []


# ---------------------------------------------------------------- 6. the adapter contract says it all

def test_the_adapter_contract_documents_every_answer_form():
    text = (HERE.parent / "adapters" / "README.md").read_text(encoding="utf-8")
    for fragment in ('"nan:<hex>"', "is the end of the run", "own decode answer", "An `op` you do not know",
                     "`rule` must then be one of the names in `vectors/imc/rules.json`"):
        assert fragment in text, fragment
    assert 'Use `"nan"`, `"inf"`, `"-inf"` for non-finite values' not in text


def test_a_nan_answered_as_a_word_fails_only_where_the_bits_are_pinned(hostile, capsys, tmp_path):
    code, doc, _ = hostile("nan-word", selection=("--id", "imc/LblRange/boundary/range/*nan*"))
    got = verdicts(doc)
    assert got["imc/LblRange/boundary/range/nan"] == "PASS"
    pinned = {cid for cid in got if cid.endswith(("nan-payload", "negative-nan"))}
    assert pinned and {got[cid] for cid in pinned} == {"FAIL"} and code == 1
    assert 'answer "nan:<hex>"' in case(doc, "imc/LblRange/boundary/range/nan-payload")["detail"]
    assert survivors(tmp_path) == []


# ---------------------------------------------------------------- 7. a protocol violation is never forgiven

@pytest.mark.parametrize("mode, what", [
    ("once-garbage", "not JSON"),
    ("once-wrong-id", "an answer to no request in flight"),
    ("once-huge", "a line over"),
    ("once-close-stdout", "closed its stdout"),
])
def test_a_one_off_protocol_violation_marks_the_case_and_the_run(hostile, tmp_path, capsys, mode, what):
    code, doc, out = hostile(mode, reports=("json", "markdown", "html"))
    terminal = capsys.readouterr().out
    assert code == 2 and doc["exit_code"] == 2
    incident = doc["incidents"][0]
    assert what in incident["reason"] and TRIGGER in incident["cases"]
    trigger = case(doc, TRIGGER)
    assert trigger["verdict"] == "PASS" and any(what in k.get("note", "") for k in trigger["checks"])
    for text in (terminal, out["markdown"].read_text(), out["html"].read_text()):
        assert what in text
    assert survivors(tmp_path) == []


# ---------------------------------------------------------------- 8. timeouts are positive and finite

@pytest.mark.parametrize("value", ["0", "-1", "nan", "inf", "soon"])
@pytest.mark.parametrize("adapter", [["--adapter", "imcpy"], ["--adapter-cmd", "python3 x.py"]])
def test_a_timeout_that_is_not_a_positive_number_is_refused(value, adapter, capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["run", *adapter, "--timeout", value, "--no-progress", "--id", "imc/LblRange/minimal"])
    assert exit_.value.code == 2
    assert "--timeout" in capsys.readouterr().err


# ---------------------------------------------------------------- 9. library adapters, loaded with care

LIBRARY = """
from imc_conformance.suites.imc import codec
from imc_conformance.adapter_api import Rejected
from imc_conformance.suites.imc.definitions import load_definitions
D = load_definitions()
class Reference:
    def hello(self): return {"implementation": "reference as a class", "suites": ["imc"], "byte_orders": ["le", "be"]}
    def encode(self, suite, message, order):
        try: return codec.encode(D, message, order)
        except codec.EncodeError as e: raise Rejected(str(e), e.rule)
    def decode(self, suite, frame):
        try: return codec.decode(D, frame)
        except codec.FrameError as e: raise Rejected(str(e), e.rule)
class RaisingHello(Reference):
    def hello(self): raise RuntimeError("no licence server")
class ListHello(Reference):
    def hello(self): return ["imc"]
class NeedsArgument(Reference):
    def __init__(self, path): pass
"""


@pytest.mark.parametrize("attr, code, fragment", [
    ("Reference", 0, None),
    ("RaisingHello", 2, "hello failed: RuntimeError: no licence server"),
    ("ListHello", 2, "hello answered a list, not an object"),
    ("NeedsArgument", 2, "cannot create the adapter"),
])
def test_library_adapters_given_as_classes(tmp_path, capsys, attr, code, fragment):
    (tmp_path / "lib.py").write_text(LIBRARY)
    assert main(["run", "--adapter", f"{tmp_path / 'lib.py'}:{attr}", "--no-progress", "--message", "LblRange"]) == code
    if fragment:
        one_line_error(capsys.readouterr().err, fragment)


# ---------------------------------------------------------------- 10. reports that cannot be written

@pytest.mark.parametrize("where", ["under-a-file", "proc"])
def test_a_report_that_cannot_be_written_is_an_error_but_the_others_are_written(tmp_path, capsys, where):
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    bad = blocker / "r.json" if where == "under-a-file" else Path("/proc/imc-conformance-report.json")
    good = tmp_path / "r.md"
    code = main(["run", "--adapter", "imcpy", "--no-progress", "--id", "imc/LblRange/minimal",
                 "--json", str(bad), "--markdown", str(good)])
    assert code == 2 and good.exists()
    err = capsys.readouterr().err
    assert "Traceback" not in err and "cannot write the json report" in err


def test_two_reports_to_one_path_is_a_usage_error(tmp_path, capsys):
    path = str(tmp_path / "r.out")
    assert main(["run", "--adapter", "imcpy", "--no-progress", "--json", path, "--html", path]) == 2
    one_line_error(capsys.readouterr().err, "--json and --html write to the same file")


# ---------------------------------------------------------------- 11. what the hello disables is shown

def test_an_adapter_that_emits_no_encoding_is_noted_everywhere_and_fails_under_strict(hostile, capsys):
    code, doc, out = hostile("no-encodings", reports=("json", "markdown", "html", "junit"))
    terminal = capsys.readouterr().out
    assert code == 0
    note = "no encode check ran"
    assert any(note in n for n in doc["notes"])
    for text in (terminal, *(p.read_text() for p in out.values())):
        assert note in text
    code, doc, _ = hostile("no-encodings", "--strict")
    assert code == 1 and doc["exit_code"] == 1


def test_an_adapter_for_another_suite_is_refused(hostile, capsys):
    code, doc, _ = hostile("wrong-suite")
    assert code == 2 and doc is None
    one_line_error(capsys.readouterr().err, "does not list the suite 'imc'")


# ---------------------------------------------------------------- 12. malformed answers are the adapter's fault

@pytest.mark.parametrize("mode, case_id, fragment", [
    ("bad-rule", "imc/LblRange/crc/footer-first-byte/le", "'no-such-rule'"),
    ("extra-field", TRIGGER, "bogus"),
    ("bad-float", TRIGGER, "'banana'"),
])
def test_malformed_answers_are_adapter_errors(hostile, capsys, tmp_path, mode, case_id, fragment):
    code, doc, _ = hostile(mode)
    got = case(doc, case_id)
    assert code == 2 and got["verdict"] == "ADAPTER_ERROR", got
    assert fragment in got["detail"] and "<object object" not in got["detail"]
    assert survivors(tmp_path) == []


# ---------------------------------------------------------------- 13. reading a saved result

@pytest.mark.parametrize("doc, fragment", [
    ([], "$: [] is not of type 'object'"),
    ({"format": "imc-conformance-result/1"}, "$: 'suite' is a required property"),
    ({"format": "imc-conformance-result/99"}, "written by a newer version of imc-conformance"),
    ({"format": "imc-conformance-result/3000"}, "written by a newer version of imc-conformance"),
    ({"format": "something-else/1"}, "not an imc-conformance result"),
])
def test_report_on_a_bad_result_says_where(tmp_path, capsys, doc, fragment):
    path = tmp_path / "r.json"
    path.write_text(json.dumps(doc))
    assert main(["report", str(path)]) == 2
    one_line_error(capsys.readouterr().err, fragment)


def test_report_on_a_result_with_a_wrong_type_inside_says_where(tmp_path, capsys):
    path = tmp_path / "r.json"
    assert main(["run", "--adapter", "imcpy", "--no-progress", "--id", "imc/LblRange/minimal", "--json", str(path)]) == 0
    doc = json.loads(path.read_text())
    doc["messages"][0]["cases"][0]["verdict"] = 7
    path.write_text(json.dumps(doc))
    capsys.readouterr()
    assert main(["report", str(path)]) == 2
    one_line_error(capsys.readouterr().err, "$.messages[0].cases[0].verdict")


# ---------------------------------------------------------------- 14. waivers are strict

@pytest.mark.parametrize("entries, fragment", [
    ([{"id": "imc/LblRange/minimal", "reason": "r", "expire": "2027-01-01"}], "$.waivers[0]: Additional properties"),
    ([{"id": "imc/LblRange/minimal", "reason": "r"}, {"id": "imc/LblRange/minimal", "reason": "again"}],
     "$.waivers[1].id: 'imc/LblRange/minimal' is waived twice"),
    ([{"id": "imc/LblRange/minimal", "reason": "r", "expires": "someday"}], "$.waivers[0].expires"),
])
def test_waivers_with_typos_or_duplicates_are_refused(tmp_path, capsys, entries, fragment):
    path = tmp_path / "waivers.json"
    path.write_text(json.dumps({"waivers": entries}))
    assert main(["run", "--adapter", "imcpy", "--no-progress", "--message", "LblRange", "--waivers", str(path)]) == 2
    one_line_error(capsys.readouterr().err, fragment)


def test_a_waiver_giving_a_key_twice_is_refused(tmp_path, capsys):
    """JSON leaves unsaid which of two equal keys counts: a waiver with two globs (one matching everything) or two
    expiry dates must not be read as either."""
    path = tmp_path / "waivers.json"
    path.write_text('{"waivers": [{"glob": "*", "reason": "r", "glob": "imc/LblRange/*"}]}')
    assert main(["run", "--adapter", "imcpy", "--no-progress", "--message", "LblRange", "--waivers", str(path)]) == 2
    one_line_error(capsys.readouterr().err, "the key 'glob' is given twice")


# ---------------------------------------------------------------- 15. a cut stderr says so

def test_a_long_stderr_says_it_was_cut_and_by_how_much(hostile, capsys):
    code, doc, _ = hostile("stderr-flood")
    assert code == 0
    assert doc["stderr"].startswith("[imc-conformance: the first 134,464 bytes of the adapter's stderr were cut]")


# ---------------------------------------------------------------- 16. list, --vectors, --version

def test_list_with_an_unknown_message_exits_2(capsys):
    assert main(["list", "--message", "NoSuchMessage"]) == 2
    one_line_error(capsys.readouterr().err, "unknown message(s): NoSuchMessage")


def test_a_missing_vectors_directory_is_named(tmp_path, capsys):
    assert main(["list", "--vectors", str(tmp_path / "nowhere")]) == 2
    one_line_error(capsys.readouterr().err, "nowhere: no such directory")


def test_vectors_accepts_the_suite_folder_as_well_as_its_cases(capsys):
    assert main(["list", "--vectors", str(imc_data()), "--message", "LblRange"]) == 0
    by_suite = capsys.readouterr().out
    assert main(["list", "--vectors", str(imc_data("cases")), "--message", "LblRange"]) == 0
    cases = json.loads(imc_data("cases", "200-LblRange.json").read_text(encoding="utf-8"))["cases"]
    assert capsys.readouterr().out == by_suite and by_suite.count("\n") == len(cases)


def test_version(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0 and capsys.readouterr().out.startswith("imc-conformance 0.")


# ---------------------------------------------------------------- 17. where the reports went

def test_a_run_prints_where_its_reports_went(tmp_path, capsys):
    path = tmp_path / "r.html"
    assert main(["run", "--adapter", "imcpy", "--no-progress", "--id", "imc/LblRange/minimal", "--html", str(path)]) == 0
    assert f"html report: {path}" in capsys.readouterr().out


# ---------------------------------------------------------------- 18. the hostile probe

PROBE = [  # mode, the trigger case's verdict (None: the run never starts), exit code
    ("reference", "PASS", 0),
    ("reversed", "PASS", 0),
    ("exit-at-once", None, 2),
    ("bad-hello", None, 2),
    ("wrong-suite", None, 2),
    ("hang", "TIMEOUT", 1),
    ("crash", "CRASH", 1),
    ("fork-exit", "CRASH", 1),
    ("crash-leaves-child", "CRASH", 1),  # its child must die at the restart, not at the end of the run
    ("liar", "FAIL", 1),
    ("hostile-text", "FAIL", 1),
    ("garbage", "ADAPTER_ERROR", 2),
    ("unknown-id", "ADAPTER_ERROR", 2),
    ("malformed", "ADAPTER_ERROR", 2),
    ("internal", "ADAPTER_ERROR", 2),
    ("hostile-internal", "ADAPTER_ERROR", 2),
    ("partial-line", "ADAPTER_ERROR", 2),
    ("huge-line", "ADAPTER_ERROR", 2),
    ("unknown-message", "ADAPTER_ERROR", 2),
    ("extra-field", "ADAPTER_ERROR", 2),
    ("bad-float", "ADAPTER_ERROR", 2),
    ("deep-json", "ADAPTER_ERROR", 2),
    ("deep-message", "ADAPTER_ERROR", 2),
    ("once-garbage", "PASS", 2),
    ("once-wrong-id", "PASS", 2),
    ("once-huge", "PASS", 2),
    ("once-close-stdout", "PASS", 2),
    ("fork-linger", "PASS", 0),
    ("stderr-flood", "PASS", 0),
    ("no-encodings", "PASS", 0),
]


@pytest.fixture(scope="module")
def reference_verdicts(tmp_path_factory):
    path = tmp_path_factory.mktemp("reference") / "r.json"
    assert main(["run", "--adapter-cmd", hostile_cmd("reference"), "--no-progress", "--message", "LblRange",
                 "--json", str(path)]) == 0
    return verdicts(json.loads(path.read_text()))


@pytest.mark.parametrize("mode, verdict, code", PROBE, ids=[p[0] for p in PROBE])
def test_hostile_probe(hostile, tmp_path, capsys, reference_verdicts, mode, verdict, code):
    got_code, doc, _ = hostile(mode)
    out, err = capsys.readouterr()
    assert got_code == code, err
    assert "Traceback" not in out + err
    assert survivors(tmp_path) == []
    if verdict is None:
        assert doc is None
        one_line_error(err)
        return
    got = verdicts(doc)
    assert got[TRIGGER] == verdict
    others = {cid: v for cid, v in got.items() if cid != TRIGGER}
    if mode == "no-encodings":  # decode checks only: cases whose checks are all encodes have none left
        assert set(others.values()) <= {"PASS", "IMPL_DEFINED", "UNSUPPORTED"}
    else:
        assert others == {cid: v for cid, v in reference_verdicts.items() if cid != TRIGGER}


def test_the_benchmark_says_plainly_when_it_misses_a_target():
    from imc_conformance import benchmark
    benchmark.COUNTS.update(library=3623, capture=1_000_000)
    lines = benchmark.target_lines({"version": 0.061, "library": 0.1, "imcpy ratio": 2.5, "capture": 15.0,
                                    "render json": 5e-6})
    assert lines == ["target --version, whole process: 61 ms (<= 100 ms): met; before: 354 ms",
                     "target in-process, imcpy: 36,230 cases/s (>= 40,000 cases/s): MISSED; before: 17,328 cases/s",
                     "target in-process, imcpy vs imcpy's bare calls: 2.50 x (<= 1.75 x): MISSED; before: 5.8 x",
                     "target JSON report per case: 5 us (<= 10 us): met",
                     "target capture judged, whole command: 66,667 frames/s (>= 150,000 frames/s): MISSED; "
                     "before: 61,614 frames/s"]
