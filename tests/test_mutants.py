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
from imc_conformance.suites.imc.corpus.coverage import load_rules
from imc_conformance.suites.imc.values import text_bytes

EDITION = "imc-5.4.30"
PASSING = {Verdict.PASS, Verdict.IMPL_DEFINED}
NOT_CAUGHT = PASSING | {Verdict.UNSUPPORTED}  # UNSUPPORTED: not tested (a refusal by a reader of no such frame)
FAIL, NON_STRICT = Verdict.FAIL, Verdict.NON_STRICT
SURVIVORS = tuple(m for m in mutants.MUTANTS if getattr(m, "equivalent", None))
KILLABLE = tuple(m for m in mutants.MUTANTS if m not in SURVIVORS and m not in mutants.NEW)  # NEW: tests/test_fuzz.py


def caught(verdicts: dict) -> dict:
    return {cid: (v, results) for cid, (v, results) in verdicts.items() if v not in NOT_CAUGHT}


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


def single_flaw(rule: str) -> Catch:
    """The cases that break ``rule`` and no other rule catch the mutant that does not check it, all with FAIL."""
    return Catch(frozenset({FAIL}), lambda c: c.get("rule") == rule and "flaws" not in c, rule=rule)


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
    """A case the reference codec accepts, with a check of one of ``ops`` (decode, encode, roundtrip): a valid one, or
    an acceptable one whose reference outcome is to accept, or that is about a practice the reference does not hold."""
    return (expectation(case, EDITION) in ("valid", "acceptable")
            and (case.get("reference", "accept") == "accept" or "practice" in case)
            and any(check.startswith(ops) for check in case["checks"]))


OVERRUNS = {"payload-cut", "length-overrun", "list-count-overrun"}
FOLLOWED = {"trailing-bytes", "truncated-then-footer", "truncated-then-frame", "payload-cut-then-frame",
            "length-overrun-then-frame", "list-count-overrun-then-frame"}  # frames with bytes after their footer


def family(case) -> str:
    return case["id"].split("/")[2]


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

    def header(pred, timestamp=False):  # (a zero timestamp re-encoded as another is permitted: class zero-timestamp)
        return lambda c: does(c, "decode", "roundtrip") and not (timestamp and c.get("class") == "zero-timestamp") \
            and pred(c["message"]["header"])

    decoded = ("decode", "roundtrip")
    encoded = ("encode", "roundtrip")
    return {
        # One mutant per MUST rule, the reference with that rule switched off: caught (FAIL) by every case that breaks
        # that rule alone, and by no other (a case listing more flaws is refused for another of them, a right rule).
        # header-truncated's is equivalent: every frame under 20 bytes also breaks size-exceeds-data (the oracle).
        **{m: single_flaw(m.off) for m in mutants.PER_RULE if not getattr(m, "equivalent", None)},
        # Every refusal named crc: NON_STRICT where the case breaks another rule and not the CRC.
        mutants.BlamesCrc: Catch(frozenset({NON_STRICT}), lambda c: c.get("rule") not in (None, "crc")
                                 and "crc" not in c.get("flaws", {}).get("rules", ())),
        # The rule's own cases are the BE frames whose CRC is stored little-endian; every other BE frame
        # is refused (FAIL), or refused under crc (NON_STRICT) where a later rule was due.
        mutants.CrcLittleEndianInBe: Catch(frozenset({FAIL, NON_STRICT}), lambda c: c["id"].endswith("/crc/wrong-byte-order/be"),
                                           within=lambda c: True, checks=be_checks),
        # Every valid frame refused (FAIL: it encodes, so it implements the messages); its refusals of invalid frames
        # show nothing, as it reads no valid one (UNSUPPORTED, not tested).
        mutants.CrcModbus: Catch(frozenset({FAIL}), lambda c: expectation(c, EDITION) == "valid",
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
        mutants.IgnoresTimestamp: Catch(frozenset({FAIL}), header(lambda h: h["timestamp"] != -1.0, timestamp=True),
                                        checks=only(*decoded)),
        # Readers and writers nobody here wrote, each caught by the corpus itself (issue: verdicts for unseen code).
        # Reading past size, it finds the fields a cut removed in the next frame (or the CRC): the overrun families
        # followed by a frame catch it (FAIL; NON_STRICT where it then stumbles on another rule), and only overruns.
        mutants.IgnoresSize: Catch(frozenset({FAIL, NON_STRICT}), lambda c: family(c).endswith("-then-frame") and family(
            c).split("-then")[0] in OVERRUNS, within=lambda c: family(c).split("-then")[0] in OVERRUNS, every=False),
        # Taking the last two bytes of the data for the CRC: the frame whose size stops short of its footer is
        # accepted (FAIL), as is a cut frame followed by a footer; anything followed by more bytes is refused naming
        # crc, a rule it does not break (NON_STRICT).
        mutants.CrcAtEndOfData: Catch(frozenset({FAIL, NON_STRICT}), lambda c: c["id"].split("/")[2:4] == [
            "crc", "footer-after-unsized-bytes"], within=lambda c: family(c) in FOLLOWED or c["id"].split("/")[2:4] == [
            "crc", "footer-after-unsized-bytes"]),
        # A timestamp of its own in every frame: every encoded frame whose given timestamp it changes (a zero one
        # excepted: stamping it is permitted, class zero-timestamp).
        mutants.RestampsTimestamps: Catch(frozenset({FAIL}), lambda c: does(c, *encoded) and c.get("class") != "zero-timestamp"
                                          and c["message"]["header"]["timestamp"] != mutants.SENDING_TIME,
                                          checks=only(*encoded)),
        mutants.CrashesOnNullElement: Catch(frozenset({Verdict.ADAPTER_ERROR}), lambda c: c.get("class") == "null-list-element"
                                            and does(c, "encode"), checks=only("encode")),
    }


# ---------------------------------------------------------------- the tests

@pytest.mark.parametrize("baseline", [mutants.Reference, mutants.Stepwise], ids=lambda m: m.name)
def test_baseline_passes_every_case(baseline, verdicts_of):
    """The unmutated adapters: the reference codec, and its decoder rebuilt check by check."""
    counts = collections.Counter(v for v, _ in verdicts_of(baseline).values())
    assert set(counts) == PASSING, counts
    assert counts[Verdict.PASS] > 3000


def test_every_must_rule_has_a_mutant(catches):
    """Every MUST rule (frame and encoder) has its switched-off mutant: caught, or equivalent with the reason why."""
    must = {r["id"] for r in load_rules() if r["level"] == "must"}
    assert {m.off for m in mutants.PER_RULE} == must
    assert sorted(c.rule for c in catches.values() if c.rule) == sorted(
        m.off for m in mutants.PER_RULE if not getattr(m, "equivalent", None))
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
