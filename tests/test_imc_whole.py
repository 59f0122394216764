"""The whole protocol (``--suite imc-full``): every message of the IMC.xml imcpy ships, the seed messages with their
own corpus, the others generated; judged by imcpy and pyimclsts (every failure an erratum), captured frames judged
message by message, and the scapy layer over all of it."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from collections import Counter

import orjson
import pytest
from scapy.compat import raw

from imc_conformance.capture.writing import PCAP_HEADER, ethernet_udp, pcap_record
from imc_conformance.cli import main
from imc_conformance.core.runner import run_cases
from imc_conformance.core.verdicts import Verdict
from imc_conformance.files import open_corpus, schema_error
from imc_conformance.paths import VECTORS
from imc_conformance.sessions.library import LibrarySession
from imc_conformance.suites import load_suite
from imc_conformance.suites.corpus import trusted
from imc_conformance.suites.imc import codec
from imc_conformance.suites.imc.corpus import samples
from imc_conformance.suites.imc.paths import IMC
from imc_conformance.suites.imc.whole import imc_xml_definitions

EDITION = "imc-5.4.30"


@pytest.fixture(scope="module")
def whole():
    return open_corpus("imc-full")


@pytest.fixture(scope="module")
def full(whole):
    return whole[0]


def seed_abbrevs() -> set[str]:
    return {m.abbrev for m in load_suite("imc").defs.suite_messages}


def test_every_message_of_imc_xml_is_a_group_and_the_seed_corpus_is_kept_as_it_is(full, whole):
    xml = imc_xml_definitions()
    assert [g.name for g in full.groups] == [m.abbrev for m in sorted(xml.messages, key=lambda m: m.id)]
    assert len(full.groups) == 338 and full.name == "imc" and full.editions[0] == EDITION
    for path in IMC.rglob("*"):  # the seeds' files, byte for byte
        name = path.relative_to(IMC).as_posix()
        if path.is_file() and name not in ("definitions.json", "manifest.json"):
            assert (full.folder / name).read_bytes() == path.read_bytes(), name
    seed = load_suite("imc").defs
    for m in seed.suite_messages:  # the seeds' definitions, clauses and editions
        assert full.defs[m.abbrev] == m
    assert full.defs["DevDataBinary"].clause == seed["DevDataBinary"].clause and not full.defs["DevDataBinary"].auxiliary
    others = {c.group for c in whole[1]} - seed_abbrevs()
    assert len(others) == 338 - len(seed.suite_messages)
    for case in whole[1]:
        if case.group in others:  # what another edition made of them is not known
            assert set(case.data["expect"]) == {EDITION}, case.id
            assert case.data["clause"].startswith(("imc-xml#", "imc-wire#")), case.id


def test_every_generated_file_passes_its_schema_and_every_case_its_definitions(full):
    """Every generated file against the schema (each file with one case of every kind it holds, which keeps this
    to seconds) and every case against the definitions."""
    schema, seeds, problems = full.schema("vector"), seed_abbrevs(), []
    for path in sorted((full.folder / "cases").glob("*.json")):
        doc = orjson.loads(path.read_bytes())
        if doc["message"]["abbrev"] in seeds:
            continue
        kinds = {}
        for case in doc["cases"]:
            kinds.setdefault("/".join(case["id"].split("/")[2:4]), case)
            problem = full.case_problem("vector", case)
            if problem:
                problems.append(f"{case['id']}: {problem}")
        problem = schema_error(schema, dict(doc, cases=list(kinds.values())), path.name)
        if problem:
            problems.append(problem)
    assert not problems, problems[:5]
    merged = orjson.loads((full.folder / "definitions.json").read_bytes())
    assert schema_error(VECTORS / "schema" / "definitions.schema.json", merged, "definitions.json") is None


def test_a_selection_reads_only_its_files_and_the_manifest_vouches_only_for_them_as_built(full, monkeypatch):
    from imc_conformance.suites import corpus

    read = []
    real = corpus.read_case_file
    monkeypatch.setattr(corpus, "read_case_file", lambda suite, kind, path: read.append(path.name) or real(suite, kind, path))
    corpus.read_cases.cache_clear()
    cases = open_corpus("imc-full", groups=frozenset({"EstimatedState"}))[1]
    assert {c.group for c in cases} == {"EstimatedState"} and read == ["350-EstimatedState.json"]
    path = full.folder / "cases" / "350-EstimatedState.json"
    assert trusted(path, path.read_bytes(), full.packaged) and not trusted(path, path.read_bytes() + b" ", full.packaged)


def judged(adapter, whole, name: str):
    suite, cases = whole
    result = run_cases(LibrarySession(adapter, name), suite, cases, edition=EDITION, adapter=name, errata=name)
    return [c for m in result.messages for c in m.cases]


@pytest.fixture(scope="module")
def imcpy_cases(whole):
    from imc_conformance.adapters.imcpy_adapter import ImcpyAdapter

    return judged(ImcpyAdapter(), whole, "imcpy")


# Erratum I5: FollowRefState cut before the field after its null inline message, alone and followed by the next frame
I5_CASES = {f"imc/FollowRefState/{family}/before-FollowRefState.reference.Reference.radius/{o}"
            for family in ("payload-cut", "payload-cut-then-frame") for o in ("le", "be")}


def test_imcpy_judged_over_the_whole_protocol_fails_only_where_an_erratum_says_why(imcpy_cases):
    cases = imcpy_cases
    verdicts = Counter(c.verdict for c in cases)
    assert verdicts[Verdict.PASS] > 40_000 and not verdicts[Verdict.ADAPTER_ERROR]
    failing = [c for c in cases if c.verdict == Verdict.FAIL]
    assert failing and all(c.errata for c in failing), [c.id for c in failing if not c.errata][:5]
    assert {c.id for c in failing if "I5" in c.errata} == I5_CASES
    unsupported = [c for c in cases if c.verdict == Verdict.UNSUPPORTED]  # erratum I6: Boolean fields cannot be read
    assert {c.id.split("/")[1] for c in unsupported} >= {"Sample", "GetWorldCoordinates"}
    # and the refusals of those messages' invalid frames show nothing: imcpy reads no valid frame of them
    assert all("imcpy's binding cannot return Sample.syringe0" in c.detail
               or "imcpy's binding cannot return GetWorldCoordinates.tracking" in c.detail
               or c.message in ("Sample", "GetWorldCoordinates") and "not tested: the implementation reads no valid "
               f"{c.message} frame" in c.detail for c in unsupported)


def test_the_imcpy_shim_gets_the_library_adapters_verdict_on_every_case(imcpy_cases, tmp_path):
    """The shim shares no code with the library adapter: told the whole protocol's definitions, it must agree."""
    assert main(["run", "--suite", "imc-full", "--adapter", "imcpy-shim", "--no-progress",
                 "--json", str(tmp_path / "shim.json")]) == 1
    doc = json.loads((tmp_path / "shim.json").read_text())
    shim = {c["id"]: c["verdict"] for m in doc["messages"] for c in m["cases"]}
    assert shim == {c.id: c.verdict.value for c in imcpy_cases}


def test_dunes_cpp_codec_judged_over_the_whole_protocol_fails_only_erratum_i5(full, whole):
    """DUNE's C++ codec without the binding (dune-cpp, built for the whole protocol's definitions): the binding's
    errata (I3, I6) are gone, DUNE's own I5 stays."""
    from imc_conformance.sessions.subprocess import SubprocessSession
    from imc_conformance.suites.imc.dune import codec as dune_codec

    program = dune_codec.program(definitions=full.packaged / "definitions.json")
    session = SubprocessSession([str(program)], name="dune-cpp", encoding_param="byte_order", hello_timeout=30)
    try:
        result = run_cases(session, full, whole[1], edition=EDITION, adapter="dune-cpp")
    finally:
        session.close()
    cases = [c for m in result.messages for c in m.cases]
    assert {c.verdict for c in cases} == {Verdict.PASS, Verdict.IMPL_DEFINED, Verdict.FAIL}
    assert {c.id for c in cases if c.verdict == Verdict.FAIL} == I5_CASES


def test_pyimclsts_judged_over_the_whole_protocol_fails_only_where_an_erratum_says_why(whole):
    from imc_conformance.adapters.pyimclsts_adapter import adapter

    cases = judged(adapter(), whole, "pyimclsts")
    verdicts = Counter(c.verdict for c in cases)
    assert verdicts[Verdict.PASS] > 25_000 and not verdicts[Verdict.ADAPTER_ERROR]
    failing = [c for c in cases if c.verdict == Verdict.FAIL]
    assert all(c.errata for c in failing), [c.id for c in failing if not c.errata][:5]


def frames_of(cases, names: tuple[str, ...]):
    for case in cases:
        if case.data.get("expect") == {EDITION: "valid"} and case.id.split("/", 2)[2] in names:
            yield case


def test_the_scapy_layer_dissects_and_builds_every_message_of_the_whole_protocol(full, whole):
    from imc_conformance.scapy import IMC as Frame, message_class, to_decoded, use_definitions

    use_definitions(full.defs)
    try:
        seen = set()
        for case in frames_of(whole[1], ("minimal", "filled")):
            for order, hexed in case.data["frames"].items():
                frame = bytes.fromhex(hexed)
                pkt = Frame(frame)
                assert to_decoded(pkt) == codec.decode(full.defs, frame), case.id
                assert raw(pkt) == frame, case.id
                seen.add(case.group)
        assert len(seen) == 338 - len(seed_abbrevs())
        assert message_class("EstimatedState").definition == full.defs["EstimatedState"]
    finally:
        use_definitions(load_suite("imc").defs)
    with pytest.raises(KeyError):
        message_class("EstimatedState")


def write_capture(path, frames: list[bytes]) -> None:
    with open(path, "wb") as out:
        out.write(PCAP_HEADER)
        for i, frame in enumerate(frames):
            out.write(pcap_record(1.7e9 + i, ethernet_udp("10.0.0.30", 6002, "10.0.0.1", 6001, frame, i)))


def test_pcap_judges_every_message_of_the_whole_protocol_frame_by_frame(full, tmp_path, capsys):
    header = {"timestamp": 1.0, "src": 30, "src_ent": 1, "dst": 0xFFFF, "dst_ent": 0xFF}
    good = [codec.encode(full.defs, {"abbrev": a, "header": header,
                                     "fields": samples.filled_fields(full.defs, full.defs[a])}, order)
            for a, order in (("EstimatedState", "le"), ("EntityState", "be"), ("Heartbeat", "le"))]
    broken = bytearray(good[0])
    broken[-1] ^= 1
    write_capture(tmp_path / "c.pcap", [*good, bytes(broken)])

    assert main(["pcap", str(tmp_path / "c.pcap"), "--json", str(tmp_path / "seed.json")]) == 1  # the broken CRC
    assert "2 frames of 2 messages the suite does not cover (framing checked only)" in capsys.readouterr().out

    assert main(["pcap", str(tmp_path / "c.pcap"), "--suite", "imc-full", "--json", str(tmp_path / "whole.json")]) == 1
    doc = json.loads((tmp_path / "whole.json").read_text())
    verdicts = {c["id"]: (c["verdict"], c["detail"]) for m in doc["messages"] for c in m["cases"]}
    assert verdicts["imc/EstimatedState/capture/frame/valid"][0] == "PASS"
    assert verdicts["imc/EntityState/capture/frame/valid"][0] == "PASS"
    assert verdicts["imc/EstimatedState/capture/frame/crc"][0] == "FAIL"
    assert "does not cover" not in " ".join(doc["notes"])


def test_a_copy_of_imc_xml_with_a_message_added_and_a_field_changed_gives_a_corpus_a_run_and_a_pcap_that_show_it(
        full, tmp_path, capsys):
    from imc_conformance.suites.imc.imc_xml import fetch_imc_xml

    raw = fetch_imc_xml().read_text(encoding="utf-8")
    start = raw.index('<message id="350"')
    end = raw.index("</message>", start)
    raw = raw[:start] + raw[start:end].replace('abbrev="height" type="fp32_t"', 'abbrev="height" type="uint8_t"') + \
        raw[end:]
    raw = raw.replace("</messages>", '<message id="4000" name="Conformance Probe" abbrev="ConformanceProbe">'
                                     '<field name="Count" abbrev="count" type="uint16_t"/></message></messages>')
    (tmp_path / "IMC.xml").write_text(raw, encoding="utf-8")
    out = tmp_path / "lab"
    assert main(["generate", "--from", str(tmp_path / "IMC.xml"), "--out", str(out)]) == 0
    assert "cases for 339 messages" in capsys.readouterr().out
    for path in (out / "cases").glob("*.json"):  # a user may keep only the messages to judge
        if not path.name.endswith(("-EstimatedState.json", "-ConformanceProbe.json", "-Heartbeat.json")):
            path.unlink()
    lab, cases = open_corpus("imc", out)
    assert lab.defs["EstimatedState"].field("height").type == "uint8_t" and lab.defs["ConformanceProbe"].id == 4000

    # imcpy, built from the unchanged IMC.xml: Heartbeat passes, the changed message fails, and the added one, of
    # which it reads no frame (it refuses them all as of an unknown id), is not tested
    from imc_conformance.adapters.imcpy_adapter import ImcpyAdapter

    result = run_cases(LibrarySession(ImcpyAdapter(), "imcpy"), lab, cases, edition=EDITION, adapter="imcpy")
    assert {m.name: m.verdict for m in result.messages} == {
        "Heartbeat": Verdict.PASS, "EstimatedState": Verdict.FAIL, "ConformanceProbe": Verdict.UNSUPPORTED}

    # frames made with the changed XML: valid by its definitions, not by IMC.xml's
    header = {"timestamp": 1.0, "src": 30, "src_ent": 1, "dst": 0xFFFF, "dst_ent": 0xFF}
    write_capture(tmp_path / "c.pcap", [
        codec.encode(lab.defs, {"abbrev": "ConformanceProbe", "header": header, "fields": {"count": 7}}, "le"),
        codec.encode(lab.defs, {"abbrev": "EstimatedState", "header": header,
                                "fields": samples.filled_fields(lab.defs, lab.defs["EstimatedState"])}, "le")])
    for args, verdicts in (
            (["--vectors", str(out)], {"imc/ConformanceProbe/capture/frame/valid": "PASS",
                                       "imc/EstimatedState/capture/frame/valid": "PASS"}),
            (["--suite", "imc-full"], {"imc/EstimatedState/capture/frame/field-overrun": "FAIL"})):
        main(["pcap", str(tmp_path / "c.pcap"), *args, "--json", str(tmp_path / "r.json")])
        doc = json.loads((tmp_path / "r.json").read_text())
        assert {c["id"]: c["verdict"] for m in doc["messages"] for c in m["cases"]} == verdicts, args
    assert "id 4000 (1)" in " ".join(doc["notes"])


def test_a_cached_imc_xml_not_as_extracted_is_extracted_again_and_never_used(tmp_path):
    """The IMC.xml in the cache is a file anyone could have changed: one that is not the pinned one is taken from the
    sdist again (here, the sdist of the cache copied: no download), and the suite is built from the real one."""
    from imc_conformance.suites.imc.imc_xml import fetch_imc_xml, imcpy_sdist

    xml = fetch_imc_xml()
    shutil.copy(imcpy_sdist(), tmp_path)
    (tmp_path / xml.name).write_text(xml.read_text(encoding="utf-8").replace('abbrev="Heartbeat"', 'abbrev="Heartbeats"',
                                                                             1), encoding="utf-8")
    done = subprocess.run([sys.executable, "-m", "imc_conformance.cli", "list", "--suite", "imc-full", "--message",
                           "Heartbeat"], capture_output=True, text=True, timeout=600, cwd=tmp_path,
                          env={**os.environ, "IMC_CONFORMANCE_CACHE": str(tmp_path)})
    assert done.returncode == 0 and done.stdout.startswith("imc/Heartbeat/"), done.stderr
    assert (tmp_path / xml.name).read_bytes() == xml.read_bytes()


def test_an_imc_xml_giving_a_seed_messages_id_another_name_is_refused_in_one_line():
    from imc_conformance.suites.imc.from_xml import XmlError, xml_document
    from imc_conformance.suites.imc.imc_xml import fetch_imc_xml
    from imc_conformance.suites.imc.whole import merged_document

    seed = json.loads((IMC / "definitions.json").read_text(encoding="utf-8"))
    xml = xml_document(fetch_imc_xml().read_bytes())
    next(m for m in xml["messages"] if m["id"] == 150).update(abbrev="Heartbeats")
    with pytest.raises(XmlError, match="<message abbrev='Heartbeats'>: id 150 is the seeds' Heartbeat"):
        merged_document(seed, xml)


def test_a_vehicles_other_traffic_is_judged_by_the_whole_protocol_live(whole):
    """With the whole protocol, a vehicle's navigation and entity traffic decodes as suite messages (a malformed one
    would fail its message) and only an id no IMC.xml defines is left to a note; no scenario fails."""
    from live_harness import run_virtual

    suite, cases = whole
    result, _ = run_virtual(suite, [c for c in cases if c.kind == "scenario"], "imc-5.4.30", variant="vehicle-traffic",
                            strict=True)
    assert result.exit_code() == 0
    assert not any("does not cover" in n for n in result.notes)
    assert any("id 999 (" in n and "no definition" in n for n in result.notes)
