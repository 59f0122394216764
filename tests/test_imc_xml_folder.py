"""Suite folders built from an IMC.xml (``generate --from IMC.xml --out DIR``): the real IMC.xml gives every
message, a custom one gives a corpus and a run that reflect its changes, and an XML the suite cannot read is a
one-line error naming the element."""

from __future__ import annotations

import json

import pytest

from imc_conformance.cli import main
from imc_conformance.core.runner import run_cases
from imc_conformance.core.verdicts import Verdict
from imc_conformance.files import open_corpus
from imc_conformance.sessions.library import LibrarySession
from imc_conformance.suites.imc.definitions import load_definitions, parse_definitions
from imc_conformance.suites.imc.from_xml import XmlError, definitions_from_xml
from imc_conformance.suites.imc.imc_xml import fetch_imc_xml
from imc_conformance.suites.imc.mutants import Reference

PACKAGED = load_definitions()
TYPES = "".join(f'<type name="{t}" size="{n}"/>' for t, n in (
    ("int8_t", 1), ("uint8_t", 1), ("int16_t", 2), ("uint16_t", 2), ("int32_t", 4), ("uint32_t", 4), ("int64_t", 8),
    ("fp32_t", 4), ("fp64_t", 8))) + '<type name="rawdata"/><type name="plaintext"/><type name="message"/>' \
    '<type name="message-list"/>'
HEADER = ('<header><field abbrev="sync" type="uint16_t" value="0xFE54"/><field abbrev="mgid" type="uint16_t"/>'
          '<field abbrev="size" type="uint16_t"/><field abbrev="timestamp" type="fp64_t"/>'
          '<field abbrev="src" type="uint16_t"/><field abbrev="src_ent" type="uint8_t"/>'
          '<field abbrev="dst" type="uint16_t"/><field abbrev="dst_ent" type="uint8_t"/></header>'
          '<footer><field abbrev="crc16" type="uint16_t"/></footer>')
MESSAGES = '''
<message id="1" name="Entity State" abbrev="EntityState">
  <field name="State" abbrev="state" type="uint8_t" unit="Enumerated" prefix="ESTA">
    <value id="0" name="Bootstrapping" abbrev="BOOT"/><value id="1" name="Normal" abbrev="NORMAL"/>
  </field>
  <field name="Flags" abbrev="flags" type="uint8_t" unit="Bitfield" bitfield-def="Flags"/>
  <field name="Description" abbrev="description" type="plaintext"/>
</message>
<message id="2" name="Holder" abbrev="Holder" flags="periodic">
  <field name="Depth" abbrev="depth" type="fp32_t" unit="m" min="0" max="100"/>
  <field name="Inner" abbrev="inner" type="message" message-type="EntityState"/>
  <field name="Items" abbrev="items" type="message-list" message-type="Group"/>
</message>'''
TABLES = ('<bitfields><def name="Flags" abbrev="Flags" prefix="FL"><value id="0x01" name="A" abbrev="A"/>'
          '<value id="0x80" name="H" abbrev="H"/></def></bitfields>'
          '<message-groups><message-group abbrev="Group"><message-type abbrev="EntityState"/></message-group>'
          '</message-groups>')


def imc_xml(messages: str = MESSAGES, version: str = "9.1.0", header: str = HEADER, tables: str = TABLES) -> bytes:
    return (f'<?xml version="1.0"?><messages name="IMC" version="{version}"><types>{TYPES}</types>{tables}{header}'
            f'{messages}</messages>').encode()


def definitions(raw: bytes) -> dict:
    return definitions_from_xml(raw, PACKAGED.raw["frame"], PACKAGED.raw["types"])


def test_the_real_imc_xml_gives_all_338_messages_and_the_seed_messages_as_definitions_json_has_them():
    doc = definitions(fetch_imc_xml().read_bytes())
    assert len(doc["messages"]) == 338 and list(doc["editions"]) == ["imc-5.4.30"]
    ours = {m.id: m for m in PACKAGED.messages}
    theirs = {m.id: m for m in parse_definitions(doc).messages}
    for mid, m in ours.items():
        t = theirs[mid]
        assert (t.abbrev, t.min_payload) == (m.abbrev, m.min_payload)
        assert [(f.abbrev, f.type, f.unit, f.minimum, f.maximum, f.enum_kind, f.message_types) for f in t.fields] == \
            [(f.abbrev, f.type, f.unit, f.minimum, f.maximum, f.enum_kind, f.message_types) for f in m.fields], m.abbrev
        for f, g in zip(m.fields, t.fields):  # the 5.4.30 table of every enumeration and bitfield
            assert {(v.value, v.abbrev) for v in g.enum_values} == \
                {(v.value, v.abbrev) for v in f.enum_values if v.editions is None or "imc-5.4.30" in v.editions}


def generated(tmp_path, name: str, raw: bytes):
    source, out = tmp_path / f"{name}.xml", tmp_path / name
    source.write_bytes(raw)
    assert main(["generate", "--from", str(source), "--out", str(out)]) == 0
    suite, cases = open_corpus("imc", out)[:2]
    return suite, cases, out


def test_a_custom_imc_xml_gives_a_corpus_and_a_run_that_reflect_its_changes(tmp_path, capsys):
    suite, cases, out = generated(tmp_path, "first", imc_xml())
    assert {c.group for c in cases} == {"EntityState", "Holder"} and suite.editions[0] == "imc-9.1.0"
    result = run_cases(LibrarySession(Reference(suite.defs), "reference"), suite, cases, edition="imc-9.1.0",
                       adapter="reference")
    assert {c.verdict for m in result.messages for c in m.cases} <= {Verdict.PASS, Verdict.IMPL_DEFINED}
    assert "cases for 2 messages of IMC 9.1.0" in capsys.readouterr().out
    doc = json.loads((out / "definitions.json").read_text())
    holder = next(m for m in doc["messages"] if m["abbrev"] == "Holder")
    assert holder["fields"][1]["message_type"]["values"] == ["EntityState"]  # a group stands for its members
    assert holder["fields"][2]["clause"] == "imc-xml#Holder.items" and holder["flags"]["values"] == ["periodic"]

    # one message added, one field changed (Holder.depth fp32 -> fp64): a new corpus that says so
    changed = MESSAGES.replace('abbrev="depth" type="fp32_t"', 'abbrev="depth" type="fp64_t"') + \
        '<message id="3" name="Extra" abbrev="Extra"><field name="N" abbrev="n" type="int16_t"/></message>'
    suite2, cases2, _ = generated(tmp_path, "second", imc_xml(changed))
    assert {c.group for c in cases2} == {"EntityState", "Holder", "Extra"}
    assert suite2.defs["Holder"].fields[0].type == "fp64_t"
    new = run_cases(LibrarySession(Reference(suite2.defs), "reference"), suite2, cases2, edition="imc-9.1.0",
                    adapter="reference")
    assert all(m.verdict in (Verdict.PASS, Verdict.IMPL_DEFINED) for m in new.messages)
    # an implementation still built from the first IMC.xml fails the changed message and knows no Extra: it reads
    # and writes no frame of it, so Extra is not tested (UNSUPPORTED), and --require Extra would fail the run
    old = run_cases(LibrarySession(Reference(suite.defs), "old build"), suite2, cases2, edition="imc-9.1.0",
                    adapter="old build")
    verdicts = {m.name: m.verdict for m in old.messages}
    assert verdicts["EntityState"] == Verdict.PASS and verdicts["Holder"] == Verdict.FAIL
    assert verdicts["Extra"] == Verdict.UNSUPPORTED
    old.required = ["Extra"]
    assert old.unmet_requirements() == ["Extra"] and old.exit_code() == 1


@pytest.mark.parametrize("raw,says", [
    (b"not xml", "not XML"),
    (b'<?xml version="1.0"?><!DOCTYPE m [<!ENTITY a "aaaa">]><messages/>', "document type"),
    (b"<nodes/>", "<nodes>: an IMC.xml's root"),
    (imc_xml(version="five"), "not an IMC version"),
    (imc_xml(MESSAGES + MESSAGES.split("</message>")[0].replace('id="1"', 'id="1"') + "</message>"), "id 1 is also"),
    (imc_xml(MESSAGES.replace('type="plaintext"', 'type="utf8"')), "<field abbrev='description'>: unknown type 'utf8'"),
    (imc_xml(tables=TABLES.replace('id="0x80"', 'id="0x100"')), "<value abbrev='H'>: 256 does not fit uint8_t"),
    (imc_xml(MESSAGES.replace('bitfield-def="Flags"', 'bitfield-def="Nope"')), "bitfield-def 'Nope' is not defined"),
    (imc_xml(MESSAGES.replace('message-type="EntityState"', 'message-type="Ghost"')), "names 'Ghost'"),
    (imc_xml(header=HEADER.replace('abbrev="dst_ent" type="uint8_t"', 'abbrev="dst_ent" type="uint16_t"')),
     "<header>: fields"),
    (imc_xml(header=HEADER.replace("0xFE54", "0xFE55")), "where the codec reads 0xFE54"),
    (imc_xml(MESSAGES.replace('min="0"', 'min="deep"')), "min 'deep' is not a number"),
])
def test_an_xml_the_suite_cannot_read_is_a_one_line_error_naming_the_element(tmp_path, capsys, raw, says):
    with pytest.raises(XmlError, match=None) as err:
        definitions(raw)
    assert says in str(err.value) and "\n" not in str(err.value)
    source = tmp_path / "IMC.xml"
    source.write_bytes(raw)
    assert main(["generate", "--from", str(source), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert says in err and err.count("\n") == 1 and "Traceback" not in err


def test_generate_from_needs_out_and_a_suite_that_builds_folders(tmp_path, capsys):
    assert main(["generate", "--from", str(tmp_path / "x.xml")]) == 2
    assert "--from FILE and --out DIR go together" in capsys.readouterr().err
    assert main(["generate", "--suite", "ros_acomms", "--from", "x", "--out", str(tmp_path)]) == 2
    assert "builds no folder" in capsys.readouterr().err


def test_a_custom_imc_xml_gives_a_pcap_judgement_that_reflects_its_changes(tmp_path, capsys):
    from imc_conformance.capture.writing import PCAP_HEADER, ethernet_udp, pcap_record
    from imc_conformance.suites.imc import codec

    _, _, first = generated(tmp_path, "first", imc_xml())
    changed = MESSAGES.replace('abbrev="depth" type="fp32_t"', 'abbrev="depth" type="fp64_t"') + \
        '<message id="3" name="Extra" abbrev="Extra"><field name="N" abbrev="n" type="int16_t"/></message>'
    suite, _, second = generated(tmp_path, "second", imc_xml(changed))
    header = {"timestamp": 1.0, "src": 30, "src_ent": 1, "dst": 0xFFFF, "dst_ent": 0xFF}
    frames = [codec.encode(suite.defs, {"abbrev": "Extra", "header": header, "fields": {"n": -2}}, "le"),
              codec.encode(suite.defs, {"abbrev": "Holder", "header": header,
                                        "fields": {"depth": 12.5, "inner": None, "items": []}}, "le")]
    with open(tmp_path / "c.pcap", "wb") as out:
        out.write(PCAP_HEADER)
        for i, frame in enumerate(frames):
            out.write(pcap_record(1.7e9 + i, ethernet_udp("10.0.0.30", 6002, "10.0.0.1", 6001, frame, i)))

    def judged(folder) -> dict:
        main(["pcap", str(tmp_path / "c.pcap"), "--vectors", str(folder), "--json", str(tmp_path / "r.json")])
        doc = json.loads((tmp_path / "r.json").read_text())
        return {c["id"]: c["verdict"] for m in doc["messages"] for c in m["cases"]}, doc["notes"]

    verdicts, _ = judged(second)  # the XML the frames were made with: both judged, both valid
    assert verdicts == {"imc/Extra/capture/frame/valid": "PASS", "imc/Holder/capture/frame/valid": "PASS"}
    fetch_imc_xml()  # the whole IMC.xml, which names the ids the folder's definitions say it defines
    verdicts, notes = judged(first)  # the XML before the change: Extra unknown, Holder's fp64 depth misread
    assert "imc/Extra/capture/frame/valid" not in verdicts and "EntityInfo (1)" in " ".join(notes)  # IMC.xml's id 3
    # Holder's fp64 depth read as fp32 leaves its inline message's id among depth's last bytes (0): an inline id no
    # definition has makes the rest of the frame unreadable, so the frame is not judged (never PASS, never FAIL)
    assert verdicts == {"imc/Holder/capture/frame/inline-outside-definitions": "INCONCLUSIVE"}
    capsys.readouterr()
    assert main(["pcap", str(tmp_path / "c.pcap"), "--vectors", str(tmp_path / "nowhere")]) == 2
    assert "no such directory" in capsys.readouterr().err
