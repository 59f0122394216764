"""ros_acomms proven against the real implementations, genpy (the canonical ROS 1 Python code, from Debian)
and rosbags, under both editions; and the corpus's power shown by mutants, each with one seeded bug.

Every failure of a real implementation must be explained by one of its documented errata, and every
erratum must still be observed; every mutant must be caught by the cases of the family it targets, and
by none outside it; the reference and the mutant whose choice is implementation-defined must pass.
"""

from __future__ import annotations

import collections
from functools import cache

import pytest
from imc_conformance.suites.ros_acomms import mutants as ros_mutants
from harness import verdicts

from imc_conformance.core.suite import erratum_keys
from imc_conformance.core.cases import expectation
from imc_conformance.core.verdicts import Verdict
from imc_conformance.files import open_corpus

EDITIONS = ("seed", "9.0.0")
PASSING = {Verdict.PASS, Verdict.IMPL_DEFINED}
SUITE, CASES = open_corpus("ros_acomms")
BY_ID = {c.id: c.data for c in CASES}


@cache
def implementation(name: str, edition: str):
    from imc_conformance.adapters.genpy_adapter import GenpyAdapter
    from imc_conformance.adapters.rosbags_adapter import RosbagsAdapter
    return {"genpy": GenpyAdapter, "rosbags": RosbagsAdapter}[name](edition=edition)


@cache
def run(name: str, edition: str) -> dict:
    return verdicts(implementation(name, edition), CASES, edition, "ros_acomms")


def failing(found: dict) -> dict:
    return {cid: results for cid, (v, results) in found.items() if v not in PASSING}


def shown(found: dict) -> list[str]:
    """The cases that fail, or where the implementation chose another outcome than the reference's."""
    return [cid for cid, (v, results) in found.items() if v not in PASSING or any(
        r.outcome is not None and r.outcome != BY_ID[cid].get("reference") for r in results)]


@pytest.mark.parametrize("edition", EDITIONS)
@pytest.mark.parametrize("name", ["genpy", "rosbags"])
def test_the_implementation_agrees_with_every_vector_but_its_documented_errata(name, edition):
    found = run(name, edition)
    unexplained = {cid: [r.detail for r in results if r.verdict not in PASSING][:2]
                   for cid, results in failing(found).items()
                   if not SUITE.implementation_errata(cid, name, BY_ID[cid]["tags"])}
    assert unexplained == {}
    counts = collections.Counter(v for v, _ in found.values())
    assert counts[Verdict.PASS] > 2500 and counts[Verdict.ADAPTER_ERROR] == 0 and counts[Verdict.NON_STRICT] == 0


@pytest.mark.parametrize("name", ["genpy", "rosbags"])
def test_every_erratum_of_the_implementation_is_still_observed(name):
    """Observed: a case it names fails, or an acceptable one got another outcome than the reference's (an erratum
    about a permitted choice, G2's lossy text, shows that way)."""
    seen = collections.Counter(e for edition in EDITIONS for cid in shown(run(name, edition))
                               for e in SUITE.implementation_errata(cid, name, BY_ID[cid]["tags"]))
    documented = {e["id"] for e in SUITE.errata
                  if name in erratum_keys(e.get("implementation")) and ("cases" in e or "tags" in e)}
    assert documented and set(seen) == documented, seen  # errata naming only generated cases: tests/test_fuzz.py


def test_every_valid_frame_is_what_both_implementations_serialize_and_describe():
    for edition in EDITIONS:
        for name in ("genpy", "rosbags"):
            found = run(name, edition)
            for case in CASES:
                if expectation(case.data, edition) != "valid" or case.id not in found:
                    continue
                explained = SUITE.implementation_errata(case.id, name, case.data["tags"])
                for r in found[case.id][1]:
                    assert r.verdict is Verdict.PASS or explained, (name, edition, case.id, r.check, r.detail)


def test_genpy_shows_the_reference_outcome_of_every_acceptable_case():
    """genpy, the canonical ROS 1 code, is the reference: its outcome is the case's, but where an erratum of its own
    says otherwise (G2: it replaces string bytes that are not UTF-8, a permitted outcome of its own)."""
    for edition in EDITIONS:
        for cid, (_, results) in run("genpy", edition).items():
            case = BY_ID[cid]
            if SUITE.implementation_errata(cid, "genpy", case["tags"]):
                continue
            for r in results:
                if r.verdict is Verdict.IMPL_DEFINED:
                    assert r.outcome == case["reference"], (cid, r.outcome)


def test_rosbags_refuses_trailing_bytes_and_genpy_accepts_them():
    outcomes = {name: {r.outcome for cid, (_, results) in run(name, "seed").items() if cid.endswith("/trailing-bytes")
                       for r in results} for name in ("genpy", "rosbags")}
    assert outcomes == {"genpy": {"accept"}, "rosbags": {"reject"}}


def test_an_implementation_with_the_9_0_0_sst_fails_sst_under_the_seed_edition():
    """rosbags holding the 9.0.0 definition (in_water_spl_dB): SST fails, by its MD5 and by its definition."""
    sst = [c for c in CASES if c.group == "SST"]
    found = verdicts(implementation("rosbags", "9.0.0"), sst, "seed", "ros_acomms")
    verdict, results = found["ros_acomms/SST/definition"]
    assert verdict is Verdict.FAIL
    assert results[0].detail == ("md5 '69e24d5bc402c8bc26c014f76173d62f', expected 73740c90b3b2c391f65fa7cc3b1d0a53; "
                                 "ros_acomms_msgs/SST: field 3 is 'float32 in_water_spl_dB', expected "
                                 "'float32 in_water_spl_db'")
    assert found["ros_acomms/SST/filled"][0] is Verdict.FAIL
    other = [c for c in CASES if c.group == "Packet"]  # a type 9.0.0 does not change passes
    assert {v for v, _ in verdicts(implementation("rosbags", "9.0.0"), other, "seed", "ros_acomms").values()} <= PASSING


# ---------------------------------------------------------------- mutants

def nests(full: str, wanted) -> bool:
    view = SUITE.defs.edition("seed")
    return any(wanted(f) for m in (view[full], *view.dependencies(view[full])) for f in m.fields)


TARGETS = {  # mutant -> (the cases that must catch it, at least one; the cases that may)
    ros_mutants.HeaderWithoutSeq: (lambda c: "valid" in c["tags"], lambda c: nests(c["type"], lambda f: f.type.base == "std_msgs/Header") or "definition" in c["tags"]),
    ros_mutants.Float32AsFloat64: (lambda c: "valid" in c["tags"], lambda c: nests(c["type"], lambda f: f.type.base == "float32")),
    ros_mutants.FixedArraysWithCount: (lambda c: c.get("class") == "fixed-array-length",
                                       lambda c: nests(c["type"], lambda f: f.type.array is not None and f.type.array >= 0)),
    ros_mutants.AcceptsTruncation: (lambda c: c.get("rule") == "truncated", lambda c: "invalid" in c["tags"] and "encode-ros1" not in c["checks"]),
    ros_mutants.ZeroesImpossibleLengths: (lambda c: c.get("rule") == "length-overrun", lambda c: "invalid" in c["tags"] and "encode-ros1" not in c["checks"]),
    ros_mutants.SignedTimeSeconds: (lambda c: {"kind:time", "class:max"} <= set(c["tags"]),
                                    lambda c: {"kind:time", "class:max"} <= set(c["tags"]) or nests(c["type"], lambda f: f.type.base == "time")),
    ros_mutants.SortedMd5: (lambda c: "definition" in c["tags"], lambda c: "definition" in c["tags"]),
    ros_mutants.DefinitionWithoutDependencies: (lambda c: "definition" in c["tags"] and nests(c["type"], lambda f: not f.type.is_builtin),
                                                lambda c: "definition" in c["tags"]),
}


@cache
def mutant_run(mutant) -> dict:
    return verdicts(mutant(), CASES, "seed", "ros_acomms")


def test_the_reference_passes_every_case():
    assert {v for v, _ in mutant_run(ros_mutants.Reference).values()} <= PASSING


@pytest.mark.parametrize("mutant", list(TARGETS), ids=lambda m: m.name)
def test_a_mutant_is_caught_by_its_family_and_only_there(mutant):
    must, may = TARGETS[mutant]
    caught = set(failing(mutant_run(mutant)))
    assert {cid for cid in caught if must(BY_ID[cid])}, "no case of its family catches it"
    assert sorted(cid for cid in caught if not may(BY_ID[cid])) == []


def test_refusing_trailing_bytes_is_implementation_defined():
    found = mutant_run(ros_mutants.RefusesTrailingBytes)
    assert failing(found) == {}
    assert {r.outcome for cid, (_, results) in found.items() if cid.endswith("trailing-bytes") for r in results} == {"reject"}


def test_wrapping_integers_is_implementation_defined():
    """The documentation does not make refusing an out-of-type integer a MUST: writing its low-order bits is the
    permitted outcome truncate, recorded and never failed."""
    found = mutant_run(ros_mutants.WrapsIntegers)
    assert failing(found) == {}
    assert {r.outcome for cid, (_, results) in found.items() if "/value-out-of-type/" in cid for r in results} == {"truncate"}


def test_every_rule_with_vectors_has_a_mutant():
    rules = {r["id"] for r in SUITE.rules if r["level"] == "must"}
    targeted = {rule for mutant, (must, _) in TARGETS.items() for rule in rules
                if any(must(c) for c in BY_ID.values() if c.get("rule") == rule)}
    assert targeted == rules
