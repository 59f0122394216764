"""adapter-check: a deliberately wrong adapter per newcomer's mistake (tests/wrong_adapter.py), each caught with the
right explanation; the reference codec and the built-in adapters pass (the C++ programs in test_cpp_adapters.py, the
starters in test_starters.py)."""

from __future__ import annotations

import shlex
import sys
from pathlib import Path

import pytest

from imc_conformance.adaptercheck.check import check as check_adapter
from imc_conformance.adaptercheck.mistakes import CATALOGUE, value_mistake
from imc_conformance.cli import main
from imc_conformance.sessions.subprocess import SubprocessSession

WRONG = Path(__file__).resolve().parent / "wrong_adapter.py"


def check(capsys, *args: str) -> tuple[int, str]:
    capsys.readouterr()
    code = main(["adapter-check", *args])
    return code, capsys.readouterr().out


def wrong(mode: str) -> list[str]:
    return ["--adapter-cmd", shlex.join([sys.executable, str(WRONG), mode]), "--timeout", "10"]


def checked(suite, cases, mode: str, timeout: float):
    """adapter-check's outcome for the wrong adapter ``mode``, its hello awaited 1 s."""
    session = SubprocessSession([sys.executable, str(WRONG), mode], name=mode, encoding_param="byte_order",
                                hello_timeout=1)
    try:
        return check_adapter(session, suite, cases, "imc-5.4.30", timeout=timeout)
    finally:
        session.close()


@pytest.mark.parametrize("mode, code, seen", [
    ("wrong-rule", "wrong-rule", "refused naming rule 'crc'; the input breaks field-overrun only"),
    ("negative-zero", "negative-zero", "header.timestamp: expected -0.0, answered 0"),
    ("nan-widened", "nan-widened", "Announce.height: expected 'nan:7fc00001', answered 'nan:7ff8000020000000'"),
    ("missing-header", "header-missing", "no dst_ent in"),
    ("header-required", "header-absent", "KeyError: 'timestamp'"),
    ("out-of-order-batch", "ordering", "is the answer to request"),
    ("no-name", "hello-fields", "the adapter's hello needs 'implementation'"),
    ("log-on-stdout", "not-json", "INFO handling hello"),
    ("unknown-op", "unknown-op", "KeyError: 'adapter-check-unknown-op'"),
    ("internal-on-accept", "internal", "no message class for id 999 (an input breaking unknown-id)"),
    ("ignores-eof", "no-exit", "it still ran 3 s after its input ended"),
    ("npe-on-null", "internal", "java.lang.NullPointerException (an inline message field holding no message (null))"),
    ("long-hello", "long-line", '{"id": 1, "ok": true, "implementation": "xxxx'),
])
def test_each_mistake_is_caught_with_its_explanation(capsys, mode, code, seen):
    status, out = check(capsys, *wrong(mode))
    what, fix = CATALOGUE[code]
    assert status == 1, out
    mistakes = [line for line in out.splitlines() if line.startswith("MISTAKE ")]
    assert mistakes == [f"MISTAKE 1: {what}" + (mistakes[0][len(f"MISTAKE 1: {what}"):] if mistakes else "")], out
    assert "the program ended before answering" not in out  # never said of what the check itself did
    assert seen in out and f"  fix:  {fix}" in out


@pytest.mark.parametrize("args", [
    [*wrong("reference")],
    ["--adapter", "imcpy"], ["--adapter", "pyimclsts"], ["--adapter", "imcpy-shim"], ["--adapter", "pyimclsts-shim"],
    ["--suite", "ros_acomms", "--adapter", "rosbags"], ["--suite", "ros_acomms", "--adapter", "reference-handler"],
])
def test_the_reference_and_the_built_in_adapters_speak_the_contract(capsys, args):
    status, out = check(capsys, *args)
    assert status == 0 and "MISTAKE" not in out and "the adapter speaks the contract" in out, out


def test_output_held_back_until_the_input_ends_is_explained(suite, cases):
    """A program whose answers wait in a buffer answers hello only once its input is closed, whatever the wait (it
    never answers before): adapter-check closes it after the hello's bound and names the buffering."""
    outcome = checked(suite, cases, "unflushed", timeout=10)
    assert [m.code for m in outcome.mistakes] == ["unflushed"]
    assert '"implementation": "hostile reference codec"' in outcome.mistakes[0].seen


def test_an_implementation_exception_on_a_null_list_element_answered_internal_is_named(capsys):
    status, out = check(capsys, *wrong("npe-on-null"))
    assert status == 1 and "MISTAKE 1: the adapter answered \"internal\": true" in out
    assert ("java.lang.NullPointerException (an input of class null-list-element, which an implementation may accept "
            "or refuse)") in out
    assert "a NullPointerException on a null list element is the implementation's" in out


def test_a_program_that_ends_once_the_check_closed_its_input_is_not_said_to_have_ended_early(suite, cases):
    """No hello answer: adapter-check closes the input to look for buffered output, and the program then exits, as the
    contract asks at the end of input. The mistake is the missing answer, never "the program ended before answering"."""
    outcome = checked(suite, cases, "silent", timeout=2)
    assert [(m.code, m.seen) for m in outcome.mistakes] == [
        ("hello-late", "no answer within 1 s, nor once adapter-check closed its input; it then exited, as it should at "
                       "the end of input")]


def test_an_adapter_that_cannot_start_is_explained(capsys, tmp_path):
    status, out = check(capsys, "--adapter-cmd", str(tmp_path / "no-such-program"))
    assert status == 1 and "MISTAKE 1: the adapter could not be started or reached" in out


@pytest.mark.parametrize("expected, actual, code", [
    (-0.0, 0, "negative-zero"), (-0.0, 0.0, "negative-zero"), (-0.0, -0.0, None),
    ("nan:7fc00001", "nan:7ff8000020000000", "nan-widened"), ("nan:7f800001", "nan:7fc00001", "nan-quieted"),
    ("nan:7fc00001", "nan:0100c07f", "nan-bytes"), ("nan:7fc00001", "nan", "nan-word"), ("nan:7fc00001", None, "nan-word"),
    ("inf", "Infinity", "inf-word"), (3.4028234663852886e38, 3.40282e38, "float-digits"), (1.5, 2.5, None),
    (1.5, 10 ** 400, None),
    ("nan:7fc00001", "nan:zz", None),
])
def test_value_mistakes_are_told_apart(expected, actual, code):
    assert value_mistake(expected, actual) == code


def test_an_implementation_canonicalising_nan_on_encode_is_its_own_result(capsys):
    """The frame alone cannot tell an implementation that canonicalises a NaN's bits from an adapter that lost them:
    both readings are shown with how to tell, and the honest adapter passes."""
    status, out = check(capsys, "--adapter", f"{Path(__file__).resolve().parent / 'nan_canonical_adapter.py'}:Adapter")
    assert status == 0 and "MISTAKE" not in out, out
    assert ("encode-le of imc/Announce/boundary/height/nan-payload: Announce.height: the request gave "
            "'nan:7fc00001', the frame holds 'nan'") in out
    assert "either the implementation writes these values so" in out and "or the adapter changed the value" in out
    assert "the adapter decoded the same probes right" in out


def test_an_adapter_that_implements_nothing_yet_is_told_so(capsys):
    status, out = check(capsys, *wrong("nothing"))
    assert status == 0 and "MISTAKE" not in out, out
    assert 'every probe was answered "unsupported": the adapter speaks the contract but implements nothing yet' in out


@pytest.mark.parametrize("command", [["run"], ["fuzz", "--budget", "5"]])
def test_run_and_fuzz_of_an_adapter_implementing_nothing_exit_2_saying_so(command, capsys):
    capsys.readouterr()
    code = main([*command, *wrong("nothing"), "--message", "LblRange"])
    out, err = capsys.readouterr()
    assert code == 2, out + err
    assert "UNSUPPORTED" in out and "PASS" not in out.split("cases in")[-1] and "agrees" not in out, out
    assert "imc-conformance: nothing could be tested: " in err and '"unsupported"' in err, err
    assert len(err.strip().splitlines()) == 1, err


def test_a_program_flooding_its_output_with_mistaken_lines_is_read_no_further_than_a_bound():
    """A program writing wrong answers without end (here: an id no request has, as fast as it can) is not read until
    the hello's wait is over, keeping every line: the check stops after a bounded number of mistakes."""
    from imc_conformance.adaptercheck.wire import Line

    class Flood:
        read = 0

        def next_event(self, wait):
            self.read += 1
            assert self.read <= 1000, "read on and on"
            return "line", b'{"id": 0, "ok": true}'

    channel = Flood()
    line = Line(channel, timeout=30.0)
    answers, mistakes = line.collect({1}, "hello", arrays=False)
    assert answers == {} and line.stopped and line.ended
    assert {m.code for m in mistakes} == {"wrong-id"} and len(mistakes) == channel.read < 1000
