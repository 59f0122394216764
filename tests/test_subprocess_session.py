"""The subprocess session: pipelining, failures pinned on the right case, start-up errors, and the shims.

The hostile adapter (``tests/hostile_adapter.py``) misbehaves in one way per mode on one case's frame;
the case must get the failure's verdict and every other case the verdict of the correct program.
The imcpy and pyimclsts shims must give the same verdicts as the library adapters over the corpus.
"""

from __future__ import annotations

import json
import subprocess
import sys
from contextlib import contextmanager
from pathlib import Path

import pytest

from harness import alive, verdicts as run_verdicts

from imc_conformance.core.cases import expectation
from imc_conformance.core.hello import check_hello
from imc_conformance.core.session import AdapterStartError, Job
from imc_conformance.core.verdicts import Verdict
from imc_conformance.files import open_corpus
from imc_conformance.sessions.library import LibrarySession
from imc_conformance.sessions.subprocess import MAX_RESTARTS, SubprocessSession

EDITION = "imc-5.4.30"
EDITIONS = ("imc-5.4.11", "imc-5.4.30")
ROOT = Path(__file__).resolve().parent.parent
HOSTILE = Path(__file__).resolve().parent / "hostile_adapter.py"
SUITE, CASES = open_corpus("imc")
KIND = SUITE.kinds["vector"]
SELECTION = [c for c in CASES if c.group in ("LblRange", "AcousticStatus")]
TRIGGER = "imc/LblRange/realistic/crosscheck"
TRIGGER_FRAME = next(c for c in SELECTION if c.id == TRIGGER).data["frames"]["le"]


@contextmanager
def session(argv: list[str], **options):
    """A session that closes; programs get 30 s to start, however short the per-request timeout."""
    name = argv[2] if len(argv) > 2 else argv[0]
    s = SubprocessSession(argv, name=name, encoding_param="byte_order", **{"hello_timeout": 30, **options})
    try:
        yield s
    finally:
        s.close()


def program(mode: str) -> list[str]:
    return [sys.executable, str(HOSTILE), mode, TRIGGER_FRAME]


def jobs_of(cases, editions=(EDITION,)) -> dict:
    """(case id, check) -> Job for every check of ``cases`` under ``editions`` (asked once if in both)."""
    jobs = {}
    for case in cases:
        for edition in editions:
            for request in KIND.plan(case.data, edition, {"le", "be"}):
                jobs.setdefault((case.id, request.check), Job("imc", case.id, request))
    return jobs


def answers_of(s, cases) -> dict:
    """The session's raw answer to every check of ``cases``, by (case id, check): what the runner judges."""
    jobs = jobs_of(cases)
    answers = {}
    for job, answer in s.run(jobs.values()):
        key = (job.case_id, job.request.check)
        assert key not in answers, f"{key} answered twice"
        answers[key] = answer
    assert answers.keys() == jobs.keys()
    return answers


def verdicts(s, cases, edition=EDITION) -> dict[str, Verdict]:
    """Case id -> verdict, through the runner."""
    return {cid: v for cid, (v, _) in run_verdicts(s, cases, edition).items()}


@pytest.fixture(scope="module")
def reference() -> dict[str, Verdict]:
    with session(program("reference")) as s:
        return verdicts(s, SELECTION)


# ---------------------------------------------------------------- broken programs

def test_the_trigger_frame_belongs_to_one_case_only():
    owners = [c.id for c in SELECTION if TRIGGER_FRAME in c.data.get("frames", {}).values()]
    assert owners == [TRIGGER]


def test_the_reference_program_passes_the_selection(reference):
    assert set(reference.values()) <= {Verdict.PASS, Verdict.IMPL_DEFINED}
    assert reference[TRIGGER] == Verdict.PASS
    assert reference.keys() == {c.id for c in SELECTION if KIND.plan(c.data, EDITION, {"le", "be"})}


@pytest.mark.parametrize("name, verdict", [
    ("hang", Verdict.TIMEOUT),
    ("crash", Verdict.CRASH),
    ("garbage", Verdict.ADAPTER_ERROR),
    ("unknown-id", Verdict.ADAPTER_ERROR),
    ("liar", Verdict.FAIL),
    ("malformed", Verdict.ADAPTER_ERROR),
    ("internal", Verdict.ADAPTER_ERROR),
])
def test_a_broken_program_fails_only_the_case_that_triggers_it(reference, name, verdict):
    with session(program(name), timeout=1) as s:
        got = verdicts(s, SELECTION)
    assert got == {**reference, TRIGGER: verdict}


def test_the_failure_reason_names_what_happened():
    with session(program("garbage"), timeout=1) as s:
        answers = answers_of(s, SELECTION)
    assert answers[TRIGGER, "decode-le"].reason == ("adapter wrote a line that is not JSON: "
                                                    "Segmentation fault? no: just garbage on stdout")


def test_stderr_is_kept_across_restarts():
    with session(program("crash"), timeout=1) as s:
        answers = answers_of(s, SELECTION)
        assert answers[TRIGGER, "decode-le"].reason == "adapter exited with code 3"
        assert "hostile: dying on the trigger frame" in s.stderr
        assert "[imc-conformance: restarting the adapter: adapter exited with code 3]" in s.stderr


def test_answers_in_any_order_are_matched_by_id(reference):
    with session(program("reversed")) as s:
        assert verdicts(s, SELECTION) == reference


@pytest.mark.parametrize("mode", ["batched", "batched-lines"])
def test_a_program_that_takes_batches_answers_as_one_per_line(reference, mode):
    """The batched protocol: several requests a line; answers as an array (in any order) or a line each."""
    with session(program(mode)) as batched:
        assert batched.hello()["batch"] is True
        assert verdicts(batched, SELECTION) == reference


def test_a_malformed_answer_in_a_batch_is_the_adapter_s_error_on_its_case(reference):
    with session(program("batched-bad")) as batched:
        got = verdicts(batched, SELECTION)
        assert got[TRIGGER] == Verdict.ADAPTER_ERROR
        assert {k: v for k, v in got.items() if k != TRIGGER} == {k: v for k, v in reference.items() if k != TRIGGER}


def test_a_program_that_keeps_crashing_cannot_hang_the_run():
    cases = SELECTION[:40]
    with session(program("always-crashes"), timeout=2) as s:
        answers = answers_of(s, cases)
    kinds = [a.kind for a in answers.values()]
    # each restart blames one call; a roundtrip shares the answer to decoding its frame (CRASH too)
    inherited = [(cid, check) for (cid, check), a in answers.items() if check.startswith("roundtrip-")
                 and a.kind == "crash" and answers.get((cid, "decode-" + check.split("-")[1])) is a]
    assert kinds.count("crash") == MAX_RESTARTS + len(inherited)
    assert kinds.count("adapter-error") == len(kinds) - kinds.count("crash")
    assert all("keeps crashing" in a.reason for a in answers.values() if a.kind == "adapter-error")  # no more restarts


def test_an_abandoned_run_leaves_the_session_usable(reference):
    with session(program("reference")) as s:
        run = s.run(jobs_of(SELECTION).values())
        next(run)
        run.close()  # with requests still in flight
        assert verdicts(s, SELECTION) == reference


RESTARTS_ONCE = """
import json, os, sys
marker = sys.argv[1]
if os.path.exists(marker):
    sys.exit("cannot start twice")
open(marker, "w").close()
for line in sys.stdin:
    request = json.loads(line)
    if request["op"] != "hello":
        os._exit(3)
    print(json.dumps({"id": request["id"], "ok": True, "implementation": "once", "suites": ["imc"],
                      "byte_orders": ["le"]}), flush=True)
"""


def test_a_program_that_cannot_be_restarted_fails_the_remaining_jobs(tmp_path):
    with session([sys.executable, "-c", RESTARTS_ONCE, str(tmp_path / "started")], timeout=2) as s:
        answers = answers_of(s, SELECTION[:10])
    assert {a.kind for a in answers.values()} == {"adapter-error"}
    assert {a.reason for a in answers.values()} == {
        "adapter could not be restarted: adapter exited with code 1 before answering hello; stderr: cannot start twice"}


# ---------------------------------------------------------------- long lines

def test_a_65536_byte_frame_and_a_131_kb_answer_go_through(reference):
    big = [c for c in SELECTION if max(map(len, c.data.get("frames", {"": ""}).values())) >= 2 * 65535]
    assert {len(f) // 2 for c in big for f in c.data["frames"].values()} == {65535, 65536}
    with session(program("reference")) as s:
        assert verdicts(s, big) == {c.id: reference[c.id] for c in big}
    # valid frames of 65,535 bytes pass; those of 65,536 (over DUNE's cap, a practice) are implementation-defined
    assert {reference[c.id] for c in big} == {Verdict.PASS, Verdict.IMPL_DEFINED}


def test_a_line_over_max_line_is_an_adapter_error(reference):
    max_line = 100_000  # a valid 65535-byte frame is a 131 KB encode answer
    too_long = {c.id for c in SELECTION if expectation(c.data, EDITION) in ("valid", "acceptable")
                and max(map(len, c.data.get("frames", {"": ""}).values())) > max_line}
    assert "imc/AcousticStatus/text/info/max-payload" in too_long
    with session(program("reference"), max_line=max_line) as s:
        got = verdicts(s, SELECTION)
    assert got == {**reference, **dict.fromkeys(too_long, Verdict.ADAPTER_ERROR)}


# ---------------------------------------------------------------- start-up errors

def python(code: str) -> list[str]:
    return [sys.executable, "-c", code]


ANSWER_HELLO = "import json, time; json.loads(input()); print(json.dumps({reply!r}), flush=True); time.sleep(60)"


@pytest.mark.parametrize("argv, message", [
    (["/nonexistent/adapter", "--flag"],
     "cannot start adapter ['/nonexistent/adapter', '--flag']: No such file or directory"),
    (python("import sys; sys.stderr.write('no IMC here'); sys.exit(4)"),
     "adapter exited with code 4 before answering hello; stderr: no IMC here"),
    (python("print('Hello, world!'); import time; time.sleep(60)"),
     "adapter answered hello with something that is not a JSON object: Hello, world!"),
    (python(ANSWER_HELLO.format(reply={"id": 1, "ok": False, "error": "no"})), "adapter refused hello: no"),
    (python(ANSWER_HELLO.format(reply={"id": 1, "ok": True})),
     "the adapter's hello needs 'implementation': a non-empty string naming it"),
])
def test_start_up_errors_are_clear(argv, message):
    s = SubprocessSession(argv, name="broken", encoding_param="byte_order", timeout=30)
    with pytest.raises(AdapterStartError) as error:
        check_hello(s.hello(), "imc", "byte_orders", ("le", "be"))
    assert str(error.value).startswith(message)
    s.close()


def test_a_program_that_never_answers_hello_times_out(tmp_path):
    pid_file = tmp_path / "pid"
    code = f"import os, time; open({str(pid_file)!r}, 'w').write(str(os.getpid())); time.sleep(600)"
    s = SubprocessSession(python(code), name="silent", encoding_param="byte_order", timeout=0.5)
    with pytest.raises(AdapterStartError, match=r"^adapter did not answer hello within 0\.5 s$"):
        s.hello()
    assert not alive(int(pid_file.read_text()))  # the program was killed, not waited for


def test_a_file_that_is_not_executable_cannot_start(tmp_path):
    script = tmp_path / "adapter.py"
    script.write_text("print('never')\n")
    with pytest.raises(AdapterStartError, match=r"cannot start adapter \[.*\]: Permission denied"):
        SubprocessSession([str(script)], name="not-executable", encoding_param="byte_order").hello()


def test_a_shim_answers_bad_requests_without_dying():
    requests = ['{"id": 1, "op": "decode", "suite": "imc", "frame": "zz"}', "not json",
                '{"id": 2, "op": "frobnicate"}', '{"id": 3, "op": "decode", "suite": "other", "frame": ""}',
                '{"id": 4, "op": "encode", "suite": "imc", "message": {"abbrev": "LblRange"}, "byte_order": "be"}',
                '{"id": 5, "op": "encode", "suite": "imc", "message": {"abbrev": "Nope"}, "byte_order": "le"}',
                '{"id": 6, "op": "decode", "suite": "imc", "frame": "' + TRIGGER_FRAME[:-4] + '0000"}']
    done = subprocess.run([sys.executable, str(ROOT / "adapters" / "imcpy_shim.py")], input="\n".join(requests) + "\n",
                          capture_output=True, text=True, timeout=60)
    replies = [json.loads(line) for line in done.stdout.splitlines()]
    assert [(r["id"], r["ok"], r.get("internal"), r.get("unsupported"), r.get("rule")) for r in replies] == [
        (1, False, True, None, None), (None, False, True, None, None), (2, False, None, True, None),
        (3, False, None, True, None), (4, False, None, True, None), (5, False, None, None, "unknown-message"),
        (6, False, None, None, "crc")]
    assert done.returncode == 0


# ---------------------------------------------------------------- the shims against the library adapters

def assert_same_verdicts(library, shim) -> None:
    for edition in EDITIONS:
        lib, sub = (run_verdicts(s, CASES, edition) for s in (library, shim))
        assert {cid: v for cid, (v, _) in sub.items()} == {cid: v for cid, (v, _) in lib.items()}
        summary = {cid: [(r.check, r.verdict, r.outcome) for r in results] for cid, (_, results) in lib.items()}
        assert {cid: [(r.check, r.verdict, r.outcome) for r in results] for cid, (_, results) in sub.items()} == summary


def test_the_imcpy_shim_gives_the_imcpy_adapters_verdicts():
    from imc_conformance.adapters.imcpy_adapter import adapter
    library = LibrarySession(adapter(), "imcpy")
    with session([sys.executable, str(ROOT / "adapters" / "imcpy_shim.py")]) as shim:
        assert shim.hello() == {**library.hello(), "batch": True}  # the shim takes batched requests
        assert_same_verdicts(library, shim)


def test_the_pyimclsts_shim_gives_the_pyimclsts_adapters_verdicts(tmp_path):
    pyimclsts_adapter = pytest.importorskip("imc_conformance.adapters.pyimclsts_adapter")
    from imc_conformance.suites.imc.imc_xml import fetch_imc_xml
    library = LibrarySession(pyimclsts_adapter.adapter(), "pyimclsts")
    argv = [sys.executable, str(ROOT / "adapters" / "pyimclsts_shim.py"),
            "--imc-xml", str(fetch_imc_xml()), "--cache", str(tmp_path)]
    with session(argv, hello_timeout=300) as shim:  # the first hello generates pyimclsts's classes
        assert shim.hello() == {**library.hello(), "batch": True}
        assert_same_verdicts(library, shim)
    assert (tmp_path / f"pyimclsts-{pyimclsts_adapter.VERSION}" / "generation.json").exists()
