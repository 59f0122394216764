"""The committed corpus is exactly what the generator builds, and its definitions are sound."""

from __future__ import annotations

import json

from imc_conformance.suites.imc import codec
from imc_conformance.suites.imc.corpus import samples
from imc_conformance.suites.imc.corpus.build import build_corpus
from imc_conformance.suites.imc.definitions import lint_definitions
from imc_conformance.suites.imc.paths import imc_data


def test_committed_corpus_has_not_drifted(defs):
    built = build_corpus(defs)
    committed = {p.relative_to(imc_data()).as_posix() for p in imc_data("cases").glob("*.json")} | {
        "coverage.md", "behaviour-coverage.md", "provenance.md"}
    assert set(built) == committed
    drifted = [name for name, text in built.items() if imc_data(name).read_text(encoding="utf-8") != text]
    assert drifted == [], "run `imc-conformance generate` and commit the result"


def test_generation_is_deterministic(defs):
    assert build_corpus(defs) == build_corpus(defs)


def test_case_ids_are_unique_and_hierarchical(records):
    ids = [c["id"] for c in records]
    assert len(ids) == len(set(ids))
    for c in records:
        suite, message, *rest = c["id"].split("/")
        assert suite == "imc" and rest and message in c["definitions"]


def test_every_case_pins_the_definitions_it_uses(records, defs):
    for c in records:
        for abbrev, digest in c["definitions"].items():
            assert defs[abbrev].hash == digest, c["id"]


def test_the_lint_finds_exactly_the_seed_erratum_666(defs):
    assert lint_definitions(defs) == [
        "AcousticStatus.status: UNSUPPORTED = 666 does not fit uint8_t [0, 255] (editions: imc-5.4.11)"]


def test_documented_minimum_payloads_match_the_codec(defs):
    for m in defs.messages:
        payload = codec.encode_payload(defs, m, samples.default_fields(m), "<")
        assert len(payload) == m.min_payload, m.abbrev


def test_examples_reproduce_the_imc_wire_cross_check_frames(defs):
    examples = json.loads(imc_data("examples.json").read_text(encoding="utf-8"))["examples"]
    pinned = [e for e in examples if "frames" in e]
    assert len(pinned) == 6
    for e in pinned:
        for order, frame in e["frames"].items():
            assert codec.encode(defs, e["message"], order).hex() == frame, (e["message"]["abbrev"], order)


def test_every_message_has_the_required_coverage(records, defs):
    for m in defs.suite_messages:
        mine = [c for c in records if c["id"].split("/")[1] == m.abbrev]
        assert sum(c["expect"] == "valid" for c in mine) >= 8, m.abbrev


def test_valid_frames_decode_to_their_message_in_the_reference_codec(records, defs):
    for c in records:
        if c["expect"] == "valid":
            for order, frame in c["frames"].items():
                assert codec.decode(defs, bytes.fromhex(frame)) == c["message"], (c["id"], order)


def test_invalid_frames_break_exactly_their_rule_in_the_reference_codec(records, defs):
    import pytest
    for c in records:
        if c["expect"] != "invalid":
            continue
        for check in c["checks"]:
            op, order = check.split("-")
            if op == "decode":
                with pytest.raises(codec.FrameError) as err:
                    codec.decode(defs, bytes.fromhex(c["frames"][order]))
                assert err.value.rule == c["rule"], (c["id"], err.value)
            else:
                with pytest.raises(codec.EncodeError) as err:
                    codec.encode(defs, c["message"], order)
                assert err.value.rule == c["rule"], c["id"]
