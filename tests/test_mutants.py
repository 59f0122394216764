"""Mutation testing of the corpus: every seeded bug of tests/mutants.py is caught, and where it should be.

"A suite that never fails proves nothing." Each mutant is the reference codec with one bug. It runs
once over the whole corpus (edition imc-5.4.30) and must be caught, a case verdict FAIL (or NON_STRICT
where the bug only changes the rule named), by the cases of the family it targets and by no case
outside the family its bug can reach. Two mutants make choices imc-wire permits and must survive.
"""

from __future__ import annotations

import collections
import math
from dataclasses import dataclass
from typing import Callable

from imc_conformance.suites.imc import mutants
import pytest
from harness import verdicts as run

from imc_conformance.core.cases import expectation
from imc_conformance.core.verdicts import Verdict
from imc_conformance.suites.imc.corpus.coverage import frame_rules
from imc_conformance.suites.imc.values import text_bytes

EDITION = "imc-5.4.30"
PASSING = {Verdict.PASS, Verdict.IMPL_DEFINED}
FAIL, NON_STRICT = Verdict.FAIL, Verdict.NON_STRICT
SURVIVORS = tuple(m for m in mutants.MUTANTS if getattr(m, "equivalent", None))
KILLABLE = tuple(m for m in mutants.MUTANTS if m not in SURVIVORS and m not in mutants.NEW)  # NEW: tests/test_fuzz.py


def caught(verdicts: dict) -> dict:
    return {cid: (v, results) for cid, (v, results) in verdicts.items() if v not in PASSING}


@pytest.fixture(scope="module")
def verdicts_of(cases, defs):
    """The verdicts of an adapter class over the corpus, each class run once."""
    cache = {}

    def verdicts_of(adapter_class):
        if adapter_class not in cache:
            cache[adapter_class] = run(adapter_class(defs), cases, EDITION)
        return cache[adapter_class]

    return verdicts_of


@pytest.fixture(scope="module")
def cases_by_id(cases):
    return {c.id: c.data for c in cases}


# ---------------------------------------------------------------- what catching each mutant means

@dataclass(frozen=True)
class Catch:
    """How the corpus must catch a mutant.

    ``verdicts``: exactly the verdicts of the catching cases. ``target``: the cases its bug aims at;
    all of them catch it (or at least one, if not ``every``). ``within``: every catching case lies
    there (default: the target). ``checks(case, check)``: every failing check is one of these.
    ``rule``: the rules.json rule whose check the mutant removes, if it is one of those.
    """

    verdicts: frozenset
    target: Callable
    within: Callable | None = None
    checks: Callable = lambda case, check: True
    every: bool = True
    rule: str | None = None


def for_rule(rule: str, *verdicts: Verdict) -> Catch:
    return Catch(frozenset(verdicts), lambda c: c.get("rule") == rule, rule=rule)


def leaves(defs, message):
    """(field definition, value) of every field of a message, inline messages and list elements included."""
    if message is None:
        return
    for f in defs[message["abbrev"]].fields:
        value = message["fields"][f.abbrev]
        yield f, value
        for inner in ([value] if f.type == "message" else value if f.type == "message-list" else []):
            yield from leaves(defs, inner)


def does(case, *ops) -> bool:
    """A case the reference accepts, with a check of one of ``ops`` (decode, encode, roundtrip)."""
    return (expectation(case, EDITION) in ("valid", "acceptable") and case.get("reference", "accept") == "accept"
            and any(check.startswith(ops) for check in case["checks"]))


def only(*ops):
    return lambda case, check: check.startswith(ops)


def be_checks(case, check) -> bool:
    return check.endswith("-be")


def nan_checks(case, check) -> bool:
    """A NaN payload shows in a re-encoded frame, and in a decoded value only where the case compares payloads."""
    return check.startswith("roundtrip") or (check.startswith("decode") and case.get("compare", {}).get("nan_payload", False))


def is_negative_zero(f, v) -> bool:
    return f.is_float and isinstance(v, float) and v == 0 and math.copysign(1, v) < 0


def is_subnormal(f, v) -> bool:
    return f.is_float and isinstance(v, float) and 0 < abs(v) < mutants.MIN_NORMAL[f.size]


def is_payload_nan(f, v) -> bool:
    return f.is_float and isinstance(v, str) and v.startswith("nan:")


def has_nul(f, v) -> bool:
    return f.type == "plaintext" and b"\0" in text_bytes(v)


@pytest.fixture(scope="module")
def catches(defs) -> dict:
    def with_field(ops, pred):
        return lambda c: does(c, *ops) and any(pred(f, v) for f, v in leaves(defs, c.get("message")))

    def header(pred):
        return lambda c: does(c, "decode", "roundtrip") and pred(c["message"]["header"])

    decoded = ("decode", "roundtrip")
    encoded = ("encode", "roundtrip")
    return {
        # A frame under 20 bytes also fails size-exceeds-data once padded: caught only through the rule named.
        mutants.PadsShortHeader: for_rule("header-truncated", NON_STRICT),
        # The sync and size cases carry a CRC over their edited bytes, so a receiver that skips the check
        # accepts them (FAIL); big-endian frames read as little-endian fail a later rule (NON_STRICT).
        mutants.AnySyncIsLittleEndian: for_rule("sync", FAIL, NON_STRICT),
        # Truncated frames lose their footer, so they still fail the CRC: NON_STRICT there, FAIL for the size edits.
        mutants.ReadsWhatIsThere: for_rule("size-exceeds-data", FAIL, NON_STRICT),
        # Accepts the real 65514-byte frames (FAIL, decode and encode); the claimed sizes then fail size-exceeds-data.
        mutants.NoSizeLimit: for_rule("size-limit", FAIL, NON_STRICT),
        # A flip in the payload can also break a length or a count: some crc cases then fail a later rule.
        mutants.NoCrcCheck: for_rule("crc", FAIL, NON_STRICT),
        mutants.UnknownIdIsEmpty: for_rule("unknown-id", FAIL),
        # A zero-padded inline id is the undefined id 0: those cases fail unknown-inline-id instead.
        mutants.PadsShortPayload: for_rule("field-overrun", FAIL, NON_STRICT),
        # Clamped text followed by more fields overruns them: field-overrun instead.
        mutants.ClampsLengths: for_rule("length-overrun", FAIL, NON_STRICT),
        mutants.ListStopsAtPayloadEnd: for_rule("list-count-overrun", FAIL),
        mutants.UnknownInlineIdIsNull: for_rule("unknown-inline-id", FAIL),
        mutants.BlamesCrc: Catch(frozenset({NON_STRICT}), lambda c: c.get("rule") not in (None, "crc")),
        # The rule's own cases are the BE frames whose CRC is stored little-endian; every other BE frame
        # is refused (FAIL), or refused under crc (NON_STRICT) where a later rule was due.
        mutants.CrcLittleEndianInBe: Catch(frozenset({FAIL, NON_STRICT}), lambda c: c["id"].endswith("/crc/wrong-byte-order/be"),
                                           within=lambda c: True, checks=be_checks),
        mutants.CrcModbus: Catch(frozenset({FAIL, NON_STRICT}), lambda c: expectation(c, EDITION) == "valid",
                                 within=lambda c: True),
        mutants.BePayloadLittleEndian: Catch(frozenset({FAIL, NON_STRICT}), lambda c: expectation(c, EDITION) == "valid",
                                             within=lambda c: True, checks=be_checks, every=False),
        mutants.DropsNegativeZero: Catch(frozenset({FAIL}), with_field(decoded, is_negative_zero), checks=only(*decoded)),
        mutants.FlushesSubnormals: Catch(frozenset({FAIL}), with_field(decoded, is_subnormal), checks=only(*decoded)),
        mutants.CanonicalNan: Catch(frozenset({FAIL}), with_field(("roundtrip",), is_payload_nan), checks=nan_checks),
        mutants.PlaintextStopsAtNul: Catch(frozenset({FAIL}), with_field(decoded, has_nul), checks=only(*decoded)),
        mutants.PlaintextLengthPlusOne: Catch(frozenset({FAIL}), with_field(encoded, lambda f, v: f.type == "plaintext"),
                                              checks=only(*encoded)),
        mutants.ListCountMinusOne: Catch(frozenset({FAIL}), with_field(encoded, lambda f, v: f.type == "message-list"),
                                         checks=only(*encoded)),
        # Every frame involving RSSI is misread: the encoded cases fail, and the decode-only acceptable
        # cases, where a plain rejection would be permitted, are rejected naming field-overrun, a rule
        # those frames do not break (NON_STRICT).
        mutants.RssiValueAsFp64: Catch(frozenset({FAIL, NON_STRICT}), lambda c: "RSSI" in c["definitions"] and does(c, "encode"),
                                       within=lambda c: "RSSI" in c["definitions"]),
        mutants.SignedSrc: Catch(frozenset({FAIL}), header(lambda h: h["src"] >= 0x8000), checks=only(*decoded)),
        mutants.IgnoresTimestamp: Catch(frozenset({FAIL}), header(lambda h: h["timestamp"] != -1.0), checks=only(*decoded)),
    }


# ---------------------------------------------------------------- the tests

@pytest.mark.parametrize("baseline", [mutants.Reference, mutants.Stepwise], ids=lambda m: m.name)
def test_baseline_passes_every_case(baseline, verdicts_of):
    """The unmutated adapters: the reference codec, and its decoder rebuilt check by check."""
    counts = collections.Counter(v for v, _ in verdicts_of(baseline).values())
    assert set(counts) == PASSING, counts
    assert counts[Verdict.PASS] > 3000


def test_every_frame_rule_has_a_mutant(catches):
    rules = {r["id"] for r in frame_rules()}
    assert sorted(c.rule for c in catches.values() if c.rule) == sorted(rules)
    assert set(catches) == set(KILLABLE)


@pytest.mark.parametrize("mutant", KILLABLE, ids=lambda m: m.name)
def test_mutant_is_caught_by_its_family(mutant, verdicts_of, catches, cases_by_id, record_property):
    expect = catches[mutant]
    verdicts = verdicts_of(mutant)
    found = caught(verdicts)
    record_property("caught", dict(collections.Counter(v.value for v, _ in found.values())))
    assert {v for v, _ in found.values()} == expect.verdicts
    targets = {cid for cid in verdicts if expect.target(cases_by_id[cid])}
    assert targets, "the target family is empty"
    if expect.every:
        assert sorted(targets - set(found)) == []
    else:
        assert targets & set(found)
    within = expect.within or expect.target
    assert sorted(cid for cid in found if not within(cases_by_id[cid])) == []
    assert sorted((cid, r.check) for cid, (_, results) in found.items() for r in results
                  if r.verdict not in PASSING and not expect.checks(cases_by_id[cid], r.check)) == []


def test_trailing_bytes_refuser_survives(verdicts_of, cases_by_id):
    """Refusing trailing bytes is a permitted choice: IMPL_DEFINED "reject", never a failure."""
    verdicts = verdicts_of(mutants.RefusesTrailingBytes)
    assert caught(verdicts) == {}
    trailing = [r for cid, (_, results) in verdicts.items() if "trailing-bytes" in cases_by_id[cid]["tags"] for r in results]
    assert trailing and all(r.verdict is Verdict.IMPL_DEFINED and r.outcome == "reject" for r in trailing)


def test_le_only_survives(verdicts_of):
    """An implementation that declares it emits only little-endian is not asked to encode big-endian."""
    verdicts = verdicts_of(mutants.LittleEndianOnly)
    assert caught(verdicts) == {}
    performed = {r.check for _, results in verdicts.values() for r in results}
    assert {"encode-le", "decode-be", "roundtrip-le"} <= performed
    assert not performed & {"encode-be", "roundtrip-be"}


def test_mutation_score(verdicts_of):
    """Every mutant but the two designed to survive is caught: mutation score 1.0 over the killable ones."""
    killed = {m for m in (*KILLABLE, *SURVIVORS) if caught(verdicts_of(m))}
    score = len(killed & set(KILLABLE)) / len(KILLABLE)
    for m in (*KILLABLE, *SURVIVORS):
        print(f"{m.name:28} {len(caught(verdicts_of(m))):5} cases catch it")
    print(f"mutation score {score:.2f} ({len(killed)}/{len(KILLABLE) + len(SURVIVORS)} caught, {len(SURVIVORS)} designed to survive)")
    assert score == 1.0
    assert not killed & set(SURVIVORS)
