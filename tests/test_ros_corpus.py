"""The ros_acomms corpus: generated deterministically, every file and case checked when loaded, a changed
definition invalidates exactly the cases that pinned it, and it runs through every kind of adapter."""

from __future__ import annotations

import json
import shlex
import shutil
import sys
from collections import Counter
from pathlib import Path

from imc_conformance.suites.ros_acomms import mutants as ros_mutants
from imc_conformance.cli import main
from imc_conformance.files import open_corpus
from imc_conformance.suites.ros_acomms.corpus.build import build_corpus
from imc_conformance.suites.ros_acomms.definitions import load_definitions
from imc_conformance.suites.ros_acomms.paths import ros_data

HERE = Path(__file__).resolve().parent


def program(mode: str) -> str:
    return shlex.join([sys.executable, str(HERE / "ros_program.py"), mode])


def test_the_committed_corpus_is_what_the_generator_builds():
    built = build_corpus(load_definitions())
    committed = {p.relative_to(ros_data()).as_posix() for p in ros_data("cases").glob("*.json")} | {
        "coverage.md", "behaviour-coverage.md", "provenance.md"}
    assert set(built) == committed
    assert [name for name, text in built.items() if ros_data(name).read_text(encoding="utf-8") != text] == []


def test_every_type_has_cases_of_every_kind_and_a_definition_check_per_edition():
    suite, cases = open_corpus("ros_acomms")
    cases = [c for c in cases if c.kind == "vector"]
    assert len({c.group for c in cases}) == 38 == len(suite.groups)
    for group in suite.groups:
        mine = [c.data for c in cases if c.group == group.name]
        kinds = Counter(k for c in mine for k in ({c["expect"]} if isinstance(c["expect"], str) else set(c["expect"].values())))
        assert kinds["valid"] >= 5 and kinds["invalid"] >= 2 and kinds["acceptable"] >= 1, group.name
        described = {e for c in mine if "describe" in c["checks"]
                     for e in (suite.editions if isinstance(c["expect"], str) else c["expect"])}
        assert described == {e for e in suite.editions if suite.defs.by_full[mine[0]["type"]].in_edition(e)}


def test_a_changed_definition_invalidates_the_cases_that_pinned_it(tmp_path, capsys):
    folder = tmp_path / "ros_acomms"
    shutil.copytree(ros_data(), folder)
    definitions = json.loads((folder / "definitions.json").read_text(encoding="utf-8"))
    packet = next(t for t in definitions["types"] if t["name"] == "Packet")
    packet["fields"][0]["name"] = "source"
    (folder / "definitions.json").write_text(json.dumps(definitions))
    assert main(["list", "--suite", "ros_acomms", "--vectors", str(folder)]) == 2
    err = capsys.readouterr().err
    assert "Packet.json: $.cases[0].md5:" in err and "is not the MD5 of ros_acomms_msgs/Packet in edition seed" in err


def test_the_subprocess_protocol_carries_types_and_describe(tmp_path, capsys):
    path = tmp_path / "r.json"
    assert main(["run", "--suite", "ros_acomms", "--adapter-cmd", program("reference"), "--no-progress",
                 "--message", "ReceivedPacket", "--message", "PingModemResponse", "--json", str(path)]) == 0
    doc = json.loads(path.read_text())
    verdicts = Counter(c["verdict"] for m in doc["messages"] for c in m["cases"])
    assert set(verdicts) <= {"PASS", "IMPL_DEFINED"} and verdicts["PASS"] > 100
    described = [c for m in doc["messages"] for c in m["cases"] if c["id"].endswith("/definition")]
    assert len(described) == 2 and {c["verdict"] for c in described} == {"PASS"}


def test_an_adapter_that_allocates_what_a_hostile_length_claims_crashes_alone(tmp_path, capsys):
    path = tmp_path / "r.json"
    code = main(["run", "--suite", "ros_acomms", "--adapter-cmd", program("allocates"), "--no-progress",
                 "--memory-limit", "256", "--id", "ros_acomms/Packet/length-overrun/*/huge", "--json", str(path)])
    doc = json.loads(path.read_text())
    cases = [c for m in doc["messages"] for c in m["cases"]]
    assert code == 1 and cases and {c["verdict"] for c in cases} == {"CRASH"}
    assert "MemoryError" in doc["stderr"]


class WrongTypes(ros_mutants.Reference):
    """Answers Packet decodes as an unknown type, and CST decodes as another type of the package."""

    name = "wrong-types"

    def decode(self, suite, frame, type="", encoding="ros1"):
        message = super().decode(suite, frame, type, encoding)
        if type == "ros_acomms_msgs/Packet":
            return dict(message, type="ros_acomms_msgs/NoSuchType")
        if type == "ros_acomms_msgs/CST":
            return dict(message, type="ros_acomms_msgs/XST")
        return message


def test_an_answer_of_an_unknown_or_other_type_is_the_adapters_fault_and_the_run_goes_on(ros):
    from harness import verdicts
    suite, cases = ros
    chosen = [c for c in cases if c.group in ("Packet", "CST", "QueueEnable")]
    found = verdicts(WrongTypes(), chosen, "seed", "ros_acomms")
    def decoded(case_id):
        verdict, checks = found[case_id]
        return verdict.value, next(k.detail for k in checks if k.check == "decode-ros1")

    verdict, detail = decoded("ros_acomms/Packet/minimal")
    assert verdict == "ADAPTER_ERROR" and "'ros_acomms_msgs/NoSuchType' is not a type of the suite" in detail
    verdict, detail = decoded("ros_acomms/CST/minimal")
    assert verdict == "ADAPTER_ERROR" and "asked for ros_acomms_msgs/CST, answered ros_acomms_msgs/XST" in detail
    assert {v.value for cid, (v, _) in found.items() if "/QueueEnable/" in cid} <= {"PASS", "IMPL_DEFINED"}


class WithoutDescribe:
    """The reference's encode and decode, without a describe operation."""

    def __init__(self):
        self.inner = ros_mutants.Reference()
        self.hello, self.encode, self.decode = self.inner.hello, self.inner.encode, self.inner.decode


def test_an_adapter_without_describe_leaves_the_definition_check_unsupported(ros):
    from harness import verdicts
    suite, cases = ros
    found = verdicts(WithoutDescribe(), [c for c in cases if c.group == "CST"], "seed", "ros_acomms")
    verdict, checks = found["ros_acomms/CST/definition"]
    assert verdict.value == "UNSUPPORTED" and "no describe operation" in checks[0].detail
    assert {v.value for cid, (v, _) in found.items() if cid != "ros_acomms/CST/definition"} <= {"PASS", "IMPL_DEFINED"}
