"""The compiled implementations: DUNE's IMC codec in C++ (``--adapter dune-cpp``) and roscpp's ROS 1 serialization
(``--adapter roscpp``), each a C++ program speaking the subprocess contract (``adapters/cpp``), built into the cache
on first use; judged on the whole corpora, both editions, beside the Python bindings of the same code; and served
over a socket (``--listen``) with the same verdicts.
"""

from __future__ import annotations

import json
import resource
import subprocess
from contextlib import contextmanager

import pytest

from harness import verdicts

from imc_conformance.cli import main as cli_main
from imc_conformance.core.verdicts import Verdict
from imc_conformance.files import open_corpus
from imc_conformance.sessions.stream_socket import SocketSession
from imc_conformance.sessions.subprocess import SubprocessSession
from imc_conformance.suites.imc.dune import codec as dune_codec
from imc_conformance.suites.ros_acomms import roscpp

PASSING = {Verdict.PASS, Verdict.IMPL_DEFINED}
IMC_SUITE, IMC_CASES = open_corpus("imc")
ROS_SUITE, ROS_CASES = open_corpus("ros_acomms")
IMC_EDITIONS = ("imc-5.4.30", "imc-5.4.11")
ROS_EDITIONS = ("seed", "9.0.0")


@pytest.fixture(scope="module")
def dune_program():
    return dune_codec.program()


@pytest.fixture(scope="module")
def roscpp_programs():
    return {edition: roscpp.program(edition) for edition in ROS_EDITIONS}


@contextmanager
def subprocess_session(program, param: str):
    session = SubprocessSession([str(program)], name=program.name, encoding_param=param, hello_timeout=30)
    try:
        yield session
    finally:
        session.close()


def memory_limit() -> None:
    """What the subprocess session does for its programs, done by whoever starts a server: the peer's memory is
    its own, and a server of roscpp must not pay for what a hostile length claims."""
    resource.setrlimit(resource.RLIMIT_DATA, (2 << 30, 2 << 30))


@contextmanager
def listening(program, where: str, param: str):
    """A socket session to the program serving ``--listen where`` (port 0: it says which port it took)."""
    server = subprocess.Popen([str(program), "--listen", where], stdout=subprocess.PIPE, text=True,
                              start_new_session=True, preexec_fn=memory_limit)
    try:
        line = server.stdout.readline().strip()
        assert line.startswith("listening "), line
        session = SocketSession(line.removeprefix("listening "), encoding_param=param, hello_timeout=30)
        try:
            yield session
        finally:
            session.close()
    finally:
        server.kill()
        server.wait()


def by_verdict(got: dict) -> dict[str, Verdict]:
    return {cid: v for cid, (v, _) in got.items()}


# ---------------------------------------------------------------- DUNE's IMC codec

@pytest.mark.parametrize("edition", IMC_EDITIONS)
def test_dune_cpp_agrees_with_imcpy_but_where_the_binding_is_wrong(dune_program, imcpy_adapter, edition):
    """Every case passes with DUNE's C++, as with imcpy; where their outcomes differ, an erratum of imcpy's binding
    says why (I3: its plaintext getters replace non-ASCII bytes; I7: its lists cannot hold null), which the C++
    codec, keeping the bytes and writing the null element, does not share."""
    with subprocess_session(dune_program, "byte_order") as session:
        assert session.hello()["errata"] == "dune"
        dune = outcomes_by_case(verdicts(session, IMC_CASES, edition))
    imcpy = outcomes_by_case(verdicts(imcpy_adapter, IMC_CASES, edition))
    assert dune.keys() == imcpy.keys()
    assert {v for v, _ in dune.values()} <= PASSING and {v for v, _ in imcpy.values()} <= PASSING
    differ = {cid for cid in dune if dune[cid] != imcpy[cid]}
    assert differ and {e for cid in differ for e in IMC_SUITE.implementation_errata(cid, "imcpy")} == {"I3", "I7"}
    assert all(IMC_SUITE.implementation_errata(cid, "imcpy") for cid in differ)


def outcomes_by_case(found: dict) -> dict:
    """Case id -> (verdict, the outcomes its checks chose)."""
    return {cid: (v, frozenset(r.outcome for r in results)) for cid, (v, results) in found.items()}


def test_dune_cpp_keeps_a_signalling_nan_that_imcpy_quiets(dune_program):
    """Erratum I4 is the binding's: DUNE's fp32_t member keeps the bits on the wire."""
    message = {"abbrev": "LblRange", "header": {}, "fields": {"id": 2, "range": "nan:7f800001"}}
    from imc_conformance.core.session import Job, Request

    with subprocess_session(dune_program, "byte_order") as session:
        [(_, encoded)] = session.run([Job("imc", "t", Request("encode-le", "encode", message=message, encoding="le"))])
        [(_, decoded)] = session.run([Job("imc", "t", Request("decode-le", "decode", frame=encoded.frame,
                                                                encoding="le"))])
    assert decoded.message["fields"]["range"] == "nan:7f800001"


def test_a_batch_whose_answers_exceed_the_line_limit_is_answered_one_a_line(dune_program):
    """Twenty decoded 65,535-byte frames are 1.3 MB of answers: more than the suite reads in one line."""
    big = next(f for c in IMC_CASES for f in c.data.get("frames", {}).values()
               if len(f) == 2 * 65535 and c.data["expect"] in ("valid", {"imc-5.4.30": "valid", "imc-5.4.11": "valid"}))
    batch = [{"id": n, "op": "decode", "suite": "imc", "frame": big} for n in range(20)]
    done = subprocess.run([str(dune_program)], input=json.dumps(batch) + "\n", capture_output=True, text=True,
                          timeout=60, check=True)
    lines = done.stdout.splitlines()
    assert len(lines) == 20 and max(map(len, lines)) < 1_000_000
    assert sorted(json.loads(line)["id"] for line in lines) == list(range(20))
    assert all(json.loads(line)["ok"] for line in lines)


def test_dune_cpp_refuses_big_endian_encoding_as_unsupported(dune_program):
    from imc_conformance.core.session import Job, Request

    message = {"abbrev": "LblRange", "header": {}, "fields": {"id": 2, "range": 1.0}}
    with subprocess_session(dune_program, "byte_order") as session:
        [(_, answer)] = session.run([Job("imc", "t", Request("encode-be", "encode", message=message, encoding="be"))])
    assert answer.kind == "unsupported"


# ---------------------------------------------------------------- roscpp

@pytest.mark.parametrize("edition", ROS_EDITIONS)
def test_roscpp_fails_only_where_it_allocates_what_a_length_claims(roscpp_programs, rosbags_adapter, edition):
    """Under the session's memory limit roscpp's resize of a 2^32 - 1 (or wrapping) array length is a CRASH
    (erratum C1); every other case passes, where rosbags and genpy fail their own errata."""
    with subprocess_session(roscpp_programs[edition], "encoding") as session:
        assert session.hello()["errata"] == "roscpp"
        got = by_verdict(verdicts(session, ROS_CASES, edition, "ros_acomms"))
    failing = {cid for cid, v in got.items() if v not in PASSING}
    assert {got[cid] for cid in failing} == {Verdict.CRASH}
    assert all("C1" in ROS_SUITE.implementation_errata(cid, "roscpp") for cid in failing)
    assert {cid.rsplit("/", 1)[1] for cid in failing} == {"huge", "wraps"}
    # a string's length is checked against the bytes left before it is copied: refused cleanly
    strings = [cid for cid in got if cid.endswith("_tags[0]/huge")]  # the first string of a string[]
    assert strings and {got[cid] for cid in strings} == {Verdict.PASS}


def test_a_fuzzer_finding_of_roscpp_s_allocation_is_labelled_with_its_erratum(roscpp_programs, tmp_path, capsys):
    """Generated frames with a length of 2^24 elements or more past the data carry huge-count: roscpp's CRASH on
    them is erratum C1, an explained finding (the fuzz run exits 0)."""
    report = tmp_path / "fuzz.json"
    code = cli_main(["fuzz", "--suite", "ros_acomms", "--adapter", "roscpp", "--message", "SoundSpeedProfile",
                     "--budget", "100", "--seed", "0", "--json", str(report)])
    crashes = [c for m in json.loads(report.read_text())["messages"] for c in m["cases"] if c["verdict"] == "CRASH"]
    assert code == 0 and crashes and all(c["errata"] == ["C1"] for c in crashes), capsys.readouterr().out[-2000:]


def test_roscpp_describes_every_type_as_the_suite_does(roscpp_programs):
    """MD5s and definitions from gencpp's traits match the suite's (the corpus's describe checks pass)."""
    describe = [c for c in ROS_CASES if any(check.startswith("describe") for check in c.data.get("checks", ()))]
    with subprocess_session(roscpp_programs["seed"], "encoding") as session:
        got = by_verdict(verdicts(session, describe, "seed", "ros_acomms"))
    assert got and set(got.values()) <= PASSING


# ---------------------------------------------------------------- over a socket

def test_dune_cpp_over_tcp_gives_the_subprocess_verdicts(dune_program):
    cases = [c for c in IMC_CASES if c.group in ("LblConfig", "AcousticRequest", "Announce")]
    with subprocess_session(dune_program, "byte_order") as session:
        direct = by_verdict(verdicts(session, cases, "imc-5.4.30"))
    with listening(dune_program, "tcp://127.0.0.1:0", "byte_order") as session:
        assert by_verdict(verdicts(session, cases, "imc-5.4.30")) == direct


def test_roscpp_over_a_unix_socket_gives_the_subprocess_verdicts(roscpp_programs, tmp_path):
    """Crashes included: the program serves each connection in a child of its own, so a bad_alloc drops that
    connection only; the session reconnects and blames the case."""
    cases = [c for c in ROS_CASES if c.group in ("SoundSpeedProfile", "CST", "QueueStatus")]
    with subprocess_session(roscpp_programs["seed"], "encoding") as session:
        direct = by_verdict(verdicts(session, cases, "seed", "ros_acomms"))
    assert Verdict.CRASH in direct.values()
    with listening(roscpp_programs["seed"], f"unix:{tmp_path / 'roscpp.sock'}", "encoding") as session:
        assert by_verdict(verdicts(session, cases, "seed", "ros_acomms")) == direct


@pytest.mark.parametrize("args", [["--adapter", "dune-cpp"], ["--suite", "ros_acomms", "--adapter", "roscpp"]])
def test_the_compiled_adapters_pass_adapter_check(args, dune_program, roscpp_programs, capsys):
    """The worked examples of the contract speak it (built above; adapter-check then starts them as a run does)."""
    assert cli_main(["adapter-check", *args]) == 0
    assert "MISTAKE" not in capsys.readouterr().out
