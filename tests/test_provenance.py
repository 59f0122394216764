"""Verdicts that hold for implementations the suite was never built with: every rule and class names its source, a
rule of practice never makes a FAIL (unless a profile holds it), every invalid vector is proven by the oracle to break
exactly the rules it names, and the choices the protocol leaves open (lossy text, a restamped zero timestamp) are
recorded, never failed."""

from __future__ import annotations

import copy
import json
import re

import pytest

from imc_conformance.adapter_api import Rejected
from imc_conformance.cli import main
from imc_conformance.kinds.vector.oracle import flaws, proof_problems
from imc_conformance.kinds.vector.provenance import held, lint
from imc_conformance.kinds.vector.texts import lossy_match
from imc_conformance.suites.imc import codec
from imc_conformance.suites.imc.corpus.oracle import case_problems, decode_refusal
from imc_conformance.suites.imc.imc_xml import fetch_imc_xml
from imc_conformance.suites.imc.paths import imc_data
from imc_conformance.suites.ros_acomms.paths import ros_data


def rules_of(data) -> dict:
    return json.loads(data("rules.json").read_text(encoding="utf-8"))


@pytest.fixture(scope="module")
def imc_rules():
    return rules_of(imc_data)


# ---------------------------------------------------------------- sources

@pytest.mark.parametrize("data", [imc_data, ros_data], ids=["imc", "ros_acomms"])
def test_every_rule_and_class_names_a_source_and_no_must_rests_on_practice(data):
    doc = rules_of(data)
    assert doc["classes"] and all(item["source"]["quotes"] for item in doc["rules"] + doc["classes"])
    assert [r["id"] for r in doc["rules"] if r["level"] == "must" and r["source"]["kind"] == "practice"] == []


def test_the_quotes_of_imc_xml_are_its_text(imc_rules):
    """Every quote from LSTS's IMC documentation is in the IMC.xml imcpy ships (whitespace aside)."""
    text = re.sub(r"\s+", " ", fetch_imc_xml().read_text(encoding="utf-8"))
    quotes = [q for item in imc_rules["rules"] + imc_rules["classes"] if item["source"]["kind"] == "imc-xml"
              for q in item["source"]["quotes"]]
    assert len(quotes) > 15 and [q for q in quotes if re.sub(r"\s+", " ", q) not in text] == []


def test_dunes_frame_cap_is_a_practice_and_its_cases_are_acceptable(imc_rules):
    size_limit = next(r for r in imc_rules["rules"] if r["id"] == "size-limit")
    assert size_limit["level"] == "practice" and size_limit["source"]["document"] == "DUNE"
    cases = [c for p in imc_data("cases").glob("*.json") for c in json.loads(p.read_text())["cases"]]
    assert not [c["id"] for c in cases if c.get("rule") == "size-limit"]
    actual = [c for c in cases if "/size-limit/actual-" in c["id"]]
    assert len(actual) == 38 and {c["expect"] for c in actual} == {"acceptable"}
    assert all(c["practice"] == "size-limit" for c in actual)


def test_the_lint_refuses_a_fail_from_a_rule_of_practice_and_an_outcome_no_class_permits(imc_rules):
    doc = copy.deepcopy(imc_rules)
    next(r for r in doc["rules"] if r["id"] == "crc")["source"] = {"kind": "practice", "document": "DUNE",
                                                                    "where": "x", "quotes": ["x"]}
    cases = {"cases": [
        {"id": "imc/X/a", "rule": "size-limit", "expect": "invalid"},
        {"id": "imc/X/b", "outcomes": [{"outcome": "lossy"}], "class": "trailing-bytes"},
        {"id": "imc/X/c", "outcomes": [{"outcome": "accept"}], "class": "no-such-class"},
    ]}
    problems = lint(doc, [cases])
    assert any("crc: level must, but its source is practice" in p for p in problems)
    assert any("imc/X/a: invalid for size-limit, a rule of practice" in p for p in problems)
    assert any("imc/X/b: outcome lossy is not one class trailing-bytes permits" in p for p in problems)
    assert any("imc/X/c: acceptable, but its class 'no-such-class'" in p for p in problems)


def test_the_provenance_tables_are_shipped():
    for data, count in ((imc_data, 16), (ros_data, 8)):
        text = data("provenance.md").read_text(encoding="utf-8")
        assert text.count("| `") >= count and "MUST" in text and "practice" in text


# ---------------------------------------------------------------- the oracle

def test_the_oracle_finds_every_rule_an_input_breaks_and_proves_the_claim():
    """A toy reference: 'a' is checked first, then 'b'; each switch off lets the input past that check."""
    def refuse(off, breaks=frozenset({"a", "b"})):
        return next((r for r in ("a", "b", "c") if r in breaks and r not in off), None)
    assert flaws(refuse, "a") == ["a", "b"]
    assert proof_problems(refuse, ["a", "b"]) == []
    assert proof_problems(refuse, ["a"]) == ["with a switched off the reference still refuses it, for b"]
    assert "not one of its flaws" in " ".join(proof_problems(refuse, ["a", "b", "c"]))
    with pytest.raises(ValueError, match="refuses it for a, not for b"):
        flaws(refuse, "b")


def test_a_crc_case_that_flips_a_length_byte_is_caught_by_the_oracle(defs):
    """The wrong reason the issue found: a flipped length byte is refused for its length by a reader without a CRC
    check; the oracle sees that the case breaks more than its rule says."""
    frame = codec.encode(defs, {"abbrev": "TextMessage", "header": {}, "fields": {"origin": "ab", "text": "cd"}}, "le")
    broken = bytearray(frame)
    broken[20] ^= 0x40  # origin's length, now claiming past the payload
    case = {"id": "imc/TextMessage/crc/payload/le", "expect": "invalid", "rule": "crc", "checks": ["decode-le"],
            "frames": {"le": bytes(broken).hex()}}
    assert decode_refusal(defs, bytes(broken)) == "crc"
    assert decode_refusal(defs, bytes(broken), frozenset({"crc"})) == "length-overrun"
    assert case_problems(defs, case) == ["decode-le: with crc switched off the reference still refuses it, for "
                                         "length-overrun"]


def test_generate_check_proves_both_corpora(capsys):
    assert main(["generate", "--check"]) == 0
    assert main(["generate", "--check", "--suite", "ros_acomms"]) == 0
    out = capsys.readouterr().out
    found = [int(n) for n in re.findall(r"oracle: (\d+) invalid cases proven", out)]
    assert len(found) == 2 and min(found) > 900
    assert len(re.findall(r"^oracle: .*[;,] 0 problems$", out, re.M)) == 2


def test_every_overrun_is_also_followed_by_more_bytes():
    """A reader that ignores size and reads on into the CRC must find bytes to read: each overrun and truncation
    family has its variants followed by the next frame (and, for a cut frame, by a CRC-correct footer)."""
    ids = {c["id"] for p in imc_data("cases").glob("*.json") for c in json.loads(p.read_text())["cases"]}
    for family in ("payload-cut", "length-overrun", "list-count-overrun"):
        plain = {i for i in ids if f"/{family}/" in i}
        followed = {i.replace(f"/{family}-then-frame/", f"/{family}/") for i in ids if f"/{family}-then-frame/" in i}
        assert plain and followed == plain, family
    assert any("/truncated-then-footer/" in i for i in ids) and any("/truncated-then-frame/" in i for i in ids)


# ---------------------------------------------------------------- what the protocol leaves open

@pytest.mark.parametrize("raw, text, ok", [
    (b"caf\xe9", "caf\ufffd", True), (b"caf\xe9", "caf?", True), (b"ol\xc3\xa1", "ol\ufffd\ufffd", True),
    (b"ol\xc3\xa1", "ol\ufffd", True), (b"ol\xc3\xa1", "olá", True), (b"\xff\xfe\xc3", "\ufffd\ufffd\ufffd", True),
    (b"caf\xe9", "café", False),  # a Latin-1 reading invents a character
    (b"caf\xe9", "caf", False),  # a byte dropped
    (b"caf\xe9", "cab\ufffd", False),  # an ASCII byte changed
    (b"abc", "abc?", False),
])
def test_lossy_text_replaces_and_never_invents(raw, text, ok):
    assert lossy_match(raw, text) is ok


def test_a_profile_holding_dunes_practice_judges_its_cases_invalid(tmp_path):
    case = {"id": "imc/X/size-limit/actual/le", "expect": "acceptable", "practice": "size-limit", "class": "size-limit",
            "outcomes": [{"outcome": "accept"}], "reference": "reject", "checks": ["decode-le"]}
    assert held(case, frozenset()) is case and held(case, frozenset({"size-limit"})) == {
        "id": case["id"], "expect": "invalid", "rule": "size-limit", "checks": ["decode-le"]}
    invalid = {"id": "imc/X/a", "expect": "invalid", "rule": "size-exceeds-data", "practice": "size-limit"}
    assert held(invalid, frozenset({"size-limit"})) is invalid
    selection = ["--id", "imc/TextMessage/size-limit/actual-*", "--no-progress"]
    for adapter, free, dune in (("imcpy", 0, 0), ("pyimclsts", 0, 1)):  # pyimclsts writes the frame over the cap
        assert main(["run", "--adapter", adapter, *selection]) == free
        assert main(["run", "--adapter", adapter, *selection, "--profile", "dune",
                     "--json", str(tmp_path / f"{adapter}.json")]) == dune
    doc = json.loads((tmp_path / "pyimclsts.json").read_text())
    assert {c["expect"] for m in doc["messages"] for c in m["cases"]} == {"invalid"}
    assert any("holds the practice size-limit: 2 cases" in n for n in doc["notes"])


def test_every_case_gives_every_header_field_it_compares():
    for path in imc_data("cases").glob("*.json"):
        for case in json.loads(path.read_text())["cases"]:
            if "message" in case:
                assert set(case["message"]["header"]) == {"timestamp", "src", "src_ent", "dst", "dst_ent"}, case["id"]


class Reference:
    """The reference codec as a library adapter; ``mangle(op, value)`` is its one departure."""

    def __init__(self, defs, mangle):
        self.defs, self.mangle = defs, mangle

    def hello(self):
        return {"implementation": "reference with a departure", "suites": ["imc"], "byte_orders": ["le", "be"]}

    def encode(self, suite, message, byte_order):
        try:
            return codec.encode(self.defs, self.mangle("encode", copy.deepcopy(message)), byte_order)
        except codec.EncodeError as exc:
            raise Rejected(exc.detail, exc.rule) from exc

    def decode(self, suite, frame):
        try:
            return self.mangle("decode", codec.decode(self.defs, frame))
        except codec.FrameError as exc:
            raise Rejected(exc.detail, exc.rule) from exc


def replace_text(message):
    fields = message["fields"]
    for name, value in fields.items():
        if isinstance(value, dict) and set(value) == {"hex"}:
            fields[name] = bytes.fromhex(value["hex"]).decode("ascii", "replace")
    return message


def zero_stamped(message):
    if message["header"]["timestamp"] == 0:
        message["header"]["timestamp"] = 1800000000.0
    return message


@pytest.mark.parametrize("op, mangle, verdict", [
    ("decode", replace_text, "IMPL_DEFINED"),  # lossy reading of text beyond ASCII: the protocol leaves it open
    ("encode", replace_text, "FAIL"),  # an encoder writes the bytes it is given, or refuses them: never others
    ("encode", zero_stamped, "IMPL_DEFINED"),  # a zero timestamp stamped with the time of sending
    ("decode", zero_stamped, "FAIL"),  # a frame's zero timestamp read as another: the bytes say 0
])
def test_the_freedoms_hold_for_their_operation_only(suite, defs, cases, op, mangle, verdict):
    from harness import verdicts as judge

    adapter = Reference(defs, lambda at, m: mangle(m) if at == op else m)
    by_id = {c.id: c.data for c in cases if c.group == "TextMessage"}
    found = judge(adapter, [c for c in cases if c.group == "TextMessage"], "imc-5.4.30")
    if mangle is replace_text:
        touched = {cid for cid, data in by_id.items() if data.get("class") == "non-ascii-text"}
    else:
        touched = {cid for cid in by_id if "/header/" in cid and "zero" in cid and cid.endswith(f"/{op}")}
    assert len(touched) >= 2 and {found[cid][0].value for cid in touched} == {verdict}
    assert {v.value for cid, (v, _) in found.items() if cid not in touched} <= {"PASS", "IMPL_DEFINED"}
