"""A gate that claims only what it observed: a refusal counts only from an implementation shown to read what it
refused, a message none of whose valid cases was tested is not PASS, every report's headline says what was tested, and
``--require`` fails a run that did not test a required message."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from imc_conformance.cli import main

HERE = Path(__file__).resolve().parent
PARTIAL = f"{HERE / 'partial_codec_adapter.py'}:Adapter"
REFUSE_ALL = f"{HERE / 'partial_codec_adapter.py'}:RefuseAll"
IMPLEMENTED = {"Heartbeat", "LblRange"}


def run(capsys, *args) -> tuple[int, str]:
    code = main(["run", "--no-progress", *args])
    out = capsys.readouterr()
    return code, out.out + out.err


@pytest.fixture(scope="module")
def partial_reports(tmp_path_factory):
    folder = tmp_path_factory.mktemp("partial")
    code = main(["run", "--no-progress", "--adapter", PARTIAL, "--json", str(folder / "r.json"), "--markdown",
                 str(folder / "r.md"), "--junit", str(folder / "r.xml"), "--html", str(folder / "r.html")])
    return code, folder


def test_a_codec_of_two_messages_passes_for_two_and_no_more(partial_reports):
    code, folder = partial_reports
    assert code == 0  # a partial implementation passes for what it does; the rest is reported as not tested
    doc = json.loads((folder / "r.json").read_text(encoding="utf-8"))
    verdicts = {m["name"]: m["verdict"] for m in doc["messages"]}
    assert len(verdicts) == 31
    assert {name for name, v in verdicts.items() if v == "PASS"} == IMPLEMENTED
    assert set(verdicts.values()) == {"PASS", "UNSUPPORTED"}
    assert doc["headline"] == "PASS for 2 of 31 messages; 29 not tested"
    # no case of an unimplemented message passes: its invalid frames' refusals show nothing
    others = [c for m in doc["messages"] if m["name"] not in IMPLEMENTED for c in m["cases"]]
    assert others and {c["verdict"] for c in others} == {"UNSUPPORTED"}
    refused = next(c for c in others if c["id"] == "imc/Announce/crc/header-src/le")
    assert refused["detail"].startswith("decode-le: not tested: the implementation reads no valid Announce frame (le)")
    markdown = (folder / "r.md").read_text(encoding="utf-8")
    assert markdown.splitlines()[0].startswith("## ✅ IMC conformance: PASS for 2 of 31 messages; 29 not tested")
    rows = [line for line in markdown.splitlines() if line.startswith("| ") and (" (1" in line or " (2" in line)]
    assert len(rows) == 31
    for line in rows:
        name = line[2:].split(" (", 1)[0]
        assert ("PASS |" in line) == (name in IMPLEMENTED), line
    assert 'name="headline" value="PASS for 2 of 31 messages; 29 not tested"' in (folder / "r.xml").read_text()
    html = (folder / "r.html").read_text(encoding="utf-8")
    assert 'id="headline">PASS for 2 of 31 messages; 29 not tested<' in html


def test_the_terminal_headline_and_the_coverage_gate(capsys):
    code, out = run(capsys, "--adapter", PARTIAL, "--message", "LblRange", "--message", "Announce")
    assert code == 0 and "PASS for 1 of 2 messages; 1 not tested" in out
    code, out = run(capsys, "--adapter", PARTIAL, "--require", "all")
    assert code == 1 and "required but not tested: Announce" in " ".join(out.split())
    assert run(capsys, "--adapter", PARTIAL, "--require", "Heartbeat", "--require", "LblRange")[0] == 0
    code, out = run(capsys, "--adapter", PARTIAL, "--require", "Nothing")
    assert code == 2 and "unknown message(s): Nothing" in out


def test_a_codec_that_refuses_everything_passes_nothing(tmp_path, capsys):
    code, out = run(capsys, "--adapter", REFUSE_ALL, "--message", "LblRange", "--message", "Sms", "--json",
                    str(tmp_path / "r.json"))
    doc = json.loads((tmp_path / "r.json").read_text(encoding="utf-8"))
    assert code == 2 and "nothing could be tested" in out
    assert not [c for m in doc["messages"] for c in m["cases"] if c["verdict"] == "PASS"]
    assert doc["headline"] == "INCONCLUSIVE, none of 2 messages tested"


def test_refusals_alone_in_a_selection_rest_on_the_base_asked_too(tmp_path, capsys):
    """Invalid cases selected alone: the valid case each was made from (its base) is asked as well, so that they are
    judged as the whole run judges them."""
    code, _ = run(capsys, "--adapter", PARTIAL, "--id", "imc/LblRange/crc/*", "--id", "imc/Sms/crc/*", "--json",
                  str(tmp_path / "r.json"))
    doc = json.loads((tmp_path / "r.json").read_text(encoding="utf-8"))
    verdicts = {m["name"]: {c["verdict"] for c in m["cases"]} for m in doc["messages"]}
    assert code == 0 and verdicts == {"Sms": {"UNSUPPORTED"}, "LblRange": {"PASS"}}


def test_every_invalid_vector_names_the_valid_case_it_was_made_from():
    from imc_conformance.files import open_corpus

    for suite_name in ("imc", "ros_acomms"):
        _, cases = open_corpus(suite_name)
        by_id = {c.id: c for c in cases}
        invalid = [c for c in cases if "invalid" in c.data.get("tags", ()) and "promoted" not in c.data.get("tags", ())
                   and c.kind == "vector"]
        assert invalid
        for case in invalid:
            base = by_id.get(case.data.get("base"))
            assert base is not None and base.group == case.group, case.id
            assert base.data["expect"] == "valid" or "valid" in base.data["expect"].values(), case.id


def test_a_message_whose_failures_are_waived_reads_waived(tmp_path, capsys):
    waivers = tmp_path / "w.json"
    waivers.write_text(json.dumps({"waivers": [{"glob": "imc/LblRange/boundary/range/*nan*", "reason": "NaN bits"}]}))
    adapter = f"{HERE / 'nan_canonical_adapter.py'}:Adapter"
    code, out = run(capsys, "--adapter", adapter, "--message", "LblRange", "--message", "Heartbeat", "--waivers",
                    str(waivers), "--json", str(tmp_path / "r.json"))
    doc = json.loads((tmp_path / "r.json").read_text(encoding="utf-8"))
    assert code == 0, out
    assert {m["name"]: m["verdict"] for m in doc["messages"]} == {"Heartbeat": "PASS", "LblRange": "WAIVED"}
    assert doc["headline"] == "PASS with waivers for all 2 messages; 1 with failures waived"


# --- adapter-check on the adapter's own messages ---------------------------------------------------------------------

NEWCOMER = HERE / "newcomer_adapter.py"


def newcomer(mode: str) -> list[str]:
    import shlex
    import sys

    return ["--adapter-cmd", shlex.join([sys.executable, str(NEWCOMER), mode]), "--timeout", "3"]


def adapter_check(capsys, *args) -> tuple[int, str]:
    capsys.readouterr()
    code = main(["adapter-check", *args])
    return code, capsys.readouterr().out


def test_a_python_adapter_writing_bare_nan_for_its_own_message_is_named(capsys):
    """A codec of Heartbeat and LblRange whose adapter writes NaN with json.dumps: the probes reach LblRange (a first
    pass finds what it reads), and the bare NaN is named with the fix in Python."""
    code, out = adapter_check(capsys, *newcomer("bare-nan"))
    assert code == 1, out
    assert "it reads 2 of 31 messages (Heartbeat, LblRange)" in out
    assert "MISTAKE 1: a line holds NaN or Infinity, which JSON does not have" in out
    assert '"range": NaN' in out and "json.dumps writes float('nan')" in out and "allow_nan=False" in out
    code, out = adapter_check(capsys, *newcomer("bare-nan"), "--message", "Heartbeat")
    assert code == 0 and "it reads 1 of 1 message (Heartbeat)" in out, out


def test_a_rule_the_implementation_names_for_one_kind_of_input_has_two_readings(capsys):
    """The implementation's transport takes the CRC from the datagram's end: a frame with bytes after it is refused
    naming crc. The adapter reports that faithfully: both readings, exit 0, the implementation's result a note."""
    code, out = adapter_check(capsys, *newcomer("crc-at-end"))
    assert code == 0 and "MISTAKE" not in out, out
    assert "trailing-bytes: named 'crc'" in out
    assert "either the implementation's own check refused it under that rule" in out
    assert "or the adapter names a rule the implementation did not give" in out and "to tell:" in out


@pytest.mark.parametrize("mode", ["hang-on-negative-zero", "crash-on-negative-zero"])
def test_the_implementation_hanging_or_dying_on_an_input_is_its_own_result(capsys, mode):
    """Issue 49, hostile probe 6: a right adapter over an implementation that hangs (or dies) on a frame holding −0.0,
    which is among the requests sent in flight together and among the probes: notes, never a mistake."""
    code, out = adapter_check(capsys, *newcomer(mode))
    assert code == 0 and "MISTAKE" not in out, out
    assert "sent again alone" in out and "the implementation hangs or dies on this input" in out
    assert "requests in flight together, each answered" not in out
    assert ("TIMEOUT" if mode.startswith("hang") else "CRASH") in out


def test_unsupported_for_frames_of_a_message_it_decodes_is_a_mistake(capsys, tmp_path):
    """Issue 49, hostile probe 7: every refusal answered "unsupported" by an adapter that decodes the valid frames of
    the same messages: a mistake with its fix; and a run never reads PASS for a message none of whose cases passed."""
    code, out = adapter_check(capsys, *newcomer("unsupported-refusals"))
    assert code == 1, out
    assert 'MISTAKE 1: "unsupported" answered for a frame of a message and byte order the adapter decodes otherwise' in out
    assert 'answer a frame it refuses {"ok": false' in out
    capsys.readouterr()
    code = main(["run", "--no-progress", *newcomer("unsupported-refusals"), "--message", "Announce", "--json",
                 str(tmp_path / "r.json")])
    doc = json.loads((tmp_path / "r.json").read_text(encoding="utf-8"))
    (announce,) = doc["messages"]
    assert announce["counts"].get("PASS", 0) > 0 and announce["verdict"] == "PASS"  # its valid cases pass
    assert {c["verdict"] for c in announce["cases"] if c["expect"] == "invalid"} == {"UNSUPPORTED"}


def test_a_message_with_no_case_passing_is_not_pass():
    from imc_conformance.core.results import CaseResult, CheckResult, message_verdict
    from imc_conformance.core.verdicts import Verdict

    def case(expect, verdict):
        return CaseResult("imc/X/c", "X", verdict, expect, "seed", [CheckResult("decode-le", verdict, "")])

    # valid cases all unsupported (e.g. every encode answered "unsupported"), an acceptable one implementation-defined
    assert message_verdict([case("valid", Verdict.UNSUPPORTED), case("acceptable", Verdict.IMPL_DEFINED),
                            case("invalid", Verdict.UNSUPPORTED)], strict=False) == "UNSUPPORTED"
    assert message_verdict([case("valid", Verdict.PASS), case("invalid", Verdict.WAIVED)], strict=False) == "WAIVED"
    assert message_verdict([case("valid", Verdict.PASS), case("invalid", Verdict.UNSUPPORTED)], strict=False) == "PASS"


def test_a_newcomer_codec_canonicalising_nan_has_a_cause_naming_what_it_wrote(tmp_path, capsys):
    code, _ = run(capsys, "--adapter", f"{HERE / 'nan_canonical_adapter.py'}:Adapter", "--message", "LblRange",
                  "--json", str(tmp_path / "r.json"))
    doc = json.loads((tmp_path / "r.json").read_text(encoding="utf-8"))
    (cause,) = doc["causes"]
    assert code == 1 and cause["key"] == "fails/encode+roundtrip/valid"
    assert cause["title"] == ("encode+roundtrip fails on valid input: class nan-payload or negative-nan; written as "
                              "'nan'; in LblRange.range")


def test_pyimclsts_with_its_waivers_by_cause_reads_waived(tmp_path, capsys):
    code, out = run(capsys, "--adapter", "pyimclsts", "--waivers", str(HERE / "data" / "pyimclsts-waivers.json"),
                    "--json", str(tmp_path / "r.json"))
    doc = json.loads((tmp_path / "r.json").read_text(encoding="utf-8"))
    assert code == 0, out
    for m in doc["messages"]:
        waived = any(c["verdict"] == "WAIVED" for c in m["cases"])
        assert m["verdict"] == ("WAIVED" if waived else "PASS"), m["name"]
    assert doc["headline"] == "PASS with waivers for all 31 messages; 31 with failures waived"


def test_the_float_adapter_the_guide_shows_is_the_one_that_passes(capsys):
    """The adapter guide's Python adapter over LblRange (a float field) is the file in docs/examples; it passes
    adapter-check and LblRange."""
    import re
    import shlex
    import sys

    docs = HERE.parent / "docs"
    page = (docs / "how-to" / "adapter.md").read_text(encoding="utf-8")
    blocks = re.findall(r"^```python\n(.*?)^```$", page, re.MULTILINE | re.DOTALL)
    program = docs / "examples" / "lblrange_adapter.py"
    assert program.read_text(encoding="utf-8") in blocks
    command = ["--adapter-cmd", shlex.join([sys.executable, str(program)])]
    code, out = adapter_check(capsys, *command)
    assert code == 0 and "it reads 1 of 31 messages (LblRange)" in out, out
    code, out = run(capsys, *command, "--message", "LblRange")
    assert code == 0 and "PASS for 1 of 1 message" in out, out


@pytest.mark.parametrize("expected, actual, code", [
    (2 ** 63 - 1, float(2 ** 63), "big-int"), (2 ** 63 - 1, 2 ** 63, "big-int"), (2 ** 63 - 1, 2 ** 63 - 1, None),
    (2 ** 63 - 1, 5, None), (7, 7.0, None)])
def test_a_large_integer_rounded_through_a_double_is_told(expected, actual, code):
    from imc_conformance.adaptercheck.mistakes import value_mistake

    assert value_mistake(expected, actual) == code
