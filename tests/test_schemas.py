"""Every JSON file under vectors/ against its JSON Schema (draft 2020-12), and the cross-file facts a schema cannot
state: rule and erratum references resolve, case ids are unique across the corpus, and so on.

The schemas are documentation for implementers in other languages, so they are also checked for being valid
draft 2020-12 schemas with an $id, a title and descriptions, and for actually rejecting broken records.
"""

from __future__ import annotations

import copy
import fnmatch
import json
from functools import cache
from pathlib import Path

import pytest
from jsonschema import Draft202012Validator

from imc_conformance.files import open_corpus
from imc_conformance.paths import VECTORS

SCHEMA_DIR = VECTORS / "schema"
ROS_SCHEMAS = ("ros_acomms-definitions", "ros_acomms-vectors", "ros_acomms-errata", "ros_acomms-examples")
SCHEMA_NAMES = ("definitions", "vectors", "rules", "errata", "examples", "scenarios", "robustness", "exchanges",
                "profile", "statements", "manifest", "ambiguities",
                *ROS_SCHEMAS, "waivers", "result", "promoted")
DRAFT = "https://json-schema.org/draft/2020-12/schema"
IMC = VECTORS / "imc"
ROS = VECTORS / "ros_acomms"
CASE_FILES = sorted((IMC / "cases").glob("*.json"))


def schema_name_for(path: Path) -> str:
    """Which schema a data file follows: imc/cases/*.json are IMC vector files, */scenarios/*.json scenario files,
    */profiles/*.json profiles, imc/<name>.json follow <name>;
    ros_acomms/cases/*.json follow ros_acomms-vectors, ros_acomms/{rules,exchanges,statements}.json the shared
    schemas, and
    ros_acomms/<name>.json ros_acomms-<name>."""
    if path.name == "manifest.json":
        return "manifest"
    if path.parent == IMC / "cases":
        return "vectors"
    if path.parent.name in ("scenarios", "robustness"):
        return path.parent.name
    if path.parent.name == "profiles":
        return "profile"
    if path.parent == IMC and path.stem in SCHEMA_NAMES:
        return path.stem
    if path.parent == ROS / "cases":
        return "ros_acomms-vectors"
    if path.parent == ROS and path.stem in ("rules", "exchanges", "statements"):
        return path.stem
    if path.parent == ROS and f"ros_acomms-{path.stem}" in SCHEMA_NAMES:
        return f"ros_acomms-{path.stem}"
    raise LookupError(f"no schema for {path}")


DATA_FILES = sorted(p for p in VECTORS.rglob("*.json") if p.parent != SCHEMA_DIR)


@cache
def load(path: Path):
    return json.loads(path.read_text(encoding="utf-8"))


@cache
def validator(name: str) -> Draft202012Validator:
    return Draft202012Validator(load(SCHEMA_DIR / f"{name}.schema.json"),
                                format_checker=Draft202012Validator.FORMAT_CHECKER)


def errors(name: str, doc) -> list[str]:
    """'<json path>: <message>' for every schema error, messages cut short (instances can be 128 KiB frames)."""
    found = sorted(validator(name).iter_errors(doc), key=lambda e: e.json_path)
    return [f"{e.json_path}: {shorten(e.message)}" for e in found]


def shorten(text: str, limit: int = 300) -> str:
    return text if len(text) <= limit else text[:limit] + f"... ({len(text)} chars)"


def all_cases():
    for path in CASE_FILES:
        for case in load(path)["cases"]:
            yield path, case


def rel(path: Path) -> str:
    return path.relative_to(VECTORS).as_posix()


# --- the schemas themselves -------------------------------------------------------------------------------------

@pytest.mark.parametrize("name", SCHEMA_NAMES)
def test_schema_is_a_valid_documented_draft_2020_12_schema(name):
    schema = load(SCHEMA_DIR / f"{name}.schema.json")
    Draft202012Validator.check_schema(schema)
    assert schema["$schema"] == DRAFT
    assert schema["$id"] == f"urn:imc-conformance:schema:{name}"
    assert schema["title"] and schema["description"]
    assert schema.get("additionalProperties") is False
    undocumented = list(undocumented_properties(schema, schema, "#"))
    assert not undocumented, f"properties without a description: {undocumented}"


def undocumented_properties(root: dict, node, where: str):
    """Declared properties (outside if/then/else/not conditions) whose schema has no description.

    A property whose schema is only a local $ref is documented by the description of the $defs entry."""
    if isinstance(node, list):
        for i, item in enumerate(node):
            yield from undocumented_properties(root, item, f"{where}/{i}")
        return
    if not isinstance(node, dict):
        return
    for key, value in node.items():
        if key in ("if", "then", "else", "not", "contains", "enum", "const"):
            continue
        if key == "properties":
            for prop, sub in value.items():
                target = root.get("$defs", {}).get(sub.get("$ref", "").removeprefix("#/$defs/"), {})
                if "description" not in sub and "description" not in target:
                    yield f"{where}/properties/{prop}"
        yield from undocumented_properties(root, value, f"{where}/{key}")


def test_every_data_file_has_a_schema_and_names_it():
    assert len(CASE_FILES) == 31 and len(list((ROS / "cases").glob("*.json"))) == 38
    for path in DATA_FILES:
        name = schema_name_for(path)
        named = (path.parent / load(path)["$schema"]).resolve()
        assert named == (SCHEMA_DIR / f"{name}.schema.json").resolve(), f"{rel(path)}: $schema points at {named}"


def test_rule_enum_of_vectors_schema_is_the_rules_a_vector_can_break():
    """The rules a case may name: the frame rules and payload-overflow, the one encoder rule with vectors (a rule of
    level 'refusal' only names an encoder's refusal)."""
    schema_rules = validator("vectors").schema["$defs"]["rule"]["enum"]
    assert schema_rules == [r["id"] for r in load(IMC / "rules.json")["rules"] if r["level"] != "refusal"]


def test_examples_schema_shares_the_decoded_form_of_vectors_schema():
    vectors, examples = (validator(n).schema["$defs"] for n in ("vectors", "examples"))
    shared = set(examples) - {"example"}
    assert shared >= {"message", "inlineMessage", "fieldValue", "floatValue", "plaintext", "frames"}
    assert {k: examples[k] for k in shared} == {k: vectors[k] for k in shared}


# --- the data files ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize("path", DATA_FILES, ids=rel)
def test_file_matches_its_schema(path):
    found = errors(schema_name_for(path), load(path))
    assert not found, f"{rel(path)}: {len(found)} schema errors:\n  " + "\n  ".join(found)


def test_case_ids_are_unique_across_the_corpus():
    seen, duplicates = {}, []
    for path, case in all_cases():
        if case["id"] in seen:
            duplicates.append(f"{case['id']} in {rel(seen[case['id']])} and {rel(path)}")
        seen[case["id"]] = path
    assert not duplicates, "\n".join(duplicates)
    assert len(seen) > 3000


def test_rules_and_errata_named_by_cases_exist():
    rules = [r["id"] for r in load(IMC / "rules.json")["rules"]]
    errata = [e["id"] for e in load(IMC / "errata.json")["errata"]]
    assert len(set(rules)) == len(rules) and len(set(errata)) == len(errata), "duplicate rule or erratum id"
    problems = []
    for path, case in all_cases():
        if "rule" in case and case["rule"] not in rules:
            problems.append(f"{rel(path)} {case['id']}: rule {case['rule']!r} is not in rules.json")
        if "erratum" in case and case["erratum"] not in errata:
            problems.append(f"{rel(path)} {case['id']}: erratum {case['erratum']!r} is not in errata.json")
    assert not problems, "\n".join(problems)


def test_cases_agree_with_their_file_and_the_definitions():
    definitions = load(IMC / "definitions.json")
    editions = list(definitions["editions"])
    abbrevs = {m["abbrev"] for m in definitions["messages"]}
    problems = []
    for path in CASE_FILES:
        doc = load(path)
        if doc["editions"] != editions:
            problems.append(f"{rel(path)}: editions {doc['editions']} != definitions.json {editions}")
        prefix = f"imc/{doc['message']['abbrev']}/"
        for case in doc["cases"]:
            where = f"{rel(path)} {case['id']}"
            if not case["id"].startswith(prefix):
                problems.append(f"{where}: id does not start with {prefix}")
            if isinstance(case["expect"], dict) and not set(case["expect"]) <= set(editions):
                problems.append(f"{where}: expect names editions outside {editions}")
            if "reference" in case and case["reference"] not in {o["outcome"] for o in case["outcomes"]}:
                problems.append(f"{where}: reference {case['reference']!r} is not one of its outcomes")
            if doc["message"]["abbrev"] not in case["definitions"] or not set(case["definitions"]) <= abbrevs:
                problems.append(f"{where}: definitions {sorted(case['definitions'])}")
    assert not problems, "\n".join(problems)


def test_erratum_case_globs_match_cases():
    """Every glob names a case of the corpus, or of the whole protocol (``--suite imc-full``)."""
    ids = [case.id for case in open_corpus("imc-full")[1]]
    empty = [f"{e['id']}: {glob}" for e in load(IMC / "errata.json")["errata"] for glob in e.get("cases", [])
             if not fnmatch.filter(ids, glob)]
    assert not empty, f"erratum case globs that match no case: {empty}"


# --- the schemas bite -------------------------------------------------------------------------------------------

def first_case(expect: str) -> tuple[dict, dict]:
    """A one-case copy of a real vector file whose case has the given string verdict."""
    for path, case in all_cases():
        if case["expect"] == expect and "message" in case:
            doc = copy.deepcopy(load(path))
            doc["cases"] = [copy.deepcopy(case)]
            return doc, doc["cases"][0]
    raise LookupError(expect)


def drop(key):
    return lambda case: case.pop(key)


def put(key, value):
    return lambda case: case.__setitem__(key, value)


def set_in(*keys_and_value):
    *keys, last, value = keys_and_value

    def mutate(case):
        node = case
        for k in keys:
            node = node[k]
        node[last] = value
    return mutate


BROKEN = {
    # (verdict of the real record to start from, mutation)
    "expect-maybe": ("valid", put("expect", "maybe")),
    "expect-bad-edition": ("valid", put("expect", {"5.4.30": "valid"})),
    "expect-empty-object": ("valid", put("expect", {})),
    "frame-odd-length": ("valid", set_in("frames", "le", "54fe9")),
    "frame-uppercase": ("valid", set_in("frames", "be", "FE54")),
    "frame-unknown-order": ("valid", set_in("frames", "xe", "00")),
    "valid-without-be-frame": ("valid", lambda c: c["frames"].pop("be")),
    "valid-without-message": ("valid", drop("message")),
    "valid-partial-header": ("valid", lambda c: c["message"]["header"].pop("src")),
    "valid-with-rule": ("valid", put("rule", "crc")),
    "valid-with-outcomes": ("valid", put("outcomes", [{"outcome": "accept"}])),
    "invalid-without-rule": ("invalid", drop("rule")),
    "unknown-rule": ("invalid", put("rule", "bad-crc")),
    "acceptable-without-outcomes": ("acceptable", drop("outcomes")),
    "acceptable-without-reference": ("acceptable", drop("reference")),
    "unknown-outcome": ("acceptable", put("outcomes", [{"outcome": "crash"}])),
    "unknown-case-key": ("valid", put("verdict", "valid")),
    "id-with-space": ("valid", put("id", "imc/LblRange/has space")),
    "id-wrong-suite": ("valid", put("id", "mavlink/Heartbeat/x")),
    "clause-unknown-document": ("valid", put("clause", "seed009#LblRange")),
    "hash-too-short": ("valid", lambda c: c["definitions"].update({k: "sha256:abc" for k in c["definitions"]})),
    "checks-empty": ("valid", put("checks", [])),
    "checks-duplicate": ("valid", put("checks", ["decode-le", "decode-le"])),
    "checks-unknown": ("valid", put("checks", ["fuzz"])),
    "erratum-bad-id": ("valid", put("erratum", "X1")),
    "tags-duplicate": ("valid", put("tags", ["valid", "valid"])),
    "compare-unknown-key": ("valid", put("compare", {"nan_bits": True})),
    "float-bad-nan-bits": ("valid", set_in("message", "header", "timestamp", "nan:7fc")),
    "header-src-too-big": ("valid", set_in("message", "header", "src", 65536)),
    "header-unknown-key": ("valid", set_in("message", "header", "mgid", 1)),
    "field-value-object": ("valid", lambda c: c["message"]["fields"].update(x={"abbrev": "LblRange"})),
    "plaintext-hex-uppercase": ("valid", lambda c: c["message"]["fields"].update(x={"hex": "AB"})),
    "list-of-numbers": ("valid", lambda c: c["message"]["fields"].update(x=[1, 2])),
    "decode-check-without-frame": ("acceptable", lambda c: (c.pop("frames"), c.update(checks=["decode-le"]))),
}


@pytest.mark.parametrize("verdict", ["valid", "invalid", "acceptable"])
def test_unbroken_sample_records_pass(verdict):
    doc, _ = first_case(verdict)
    assert errors("vectors", doc) == []


@pytest.mark.parametrize("breakage", BROKEN)
def test_schema_rejects_a_broken_record(breakage):
    verdict, mutate = BROKEN[breakage]
    doc, case = first_case(verdict)
    mutate(case)
    found = errors("vectors", doc)
    assert found, f"{breakage}: the schema accepted {shorten(json.dumps(case), 2000)}"
    assert all(e.startswith("$.cases[0]") for e in found), found


def test_schema_rejects_broken_file_level_keys():
    doc, _ = first_case("valid")
    for key, value in [("format", 2), ("suite", "mavlink"), ("editions", ["5.4.30"]), ("extra", 1)]:
        broken = {**doc, key: value}
        assert errors("vectors", broken), f"{key}={value!r} accepted"
    assert errors("vectors", {k: v for k, v in doc.items() if k != "cases"})


@pytest.mark.parametrize("name, mutate", [
    ("definitions", lambda d: d["messages"][0].update(id="150")),
    ("definitions", lambda d: d["messages"][1]["fields"][0].update(type="string")),
    ("definitions", lambda d: d["messages"][1]["fields"][1]["enum"].update(kind="set")),
    ("definitions", lambda d: d["messages"][1]["fields"][0].update(enum=d["messages"][1]["fields"][1]["enum"])),
    ("rules", lambda d: d["rules"][0].update(applies_to="some")),
    ("errata", lambda d: d["errata"][0].pop("real")),
    ("errata", lambda d: d["errata"][0].update(kind="implementation")),
    ("examples", lambda d: d["examples"][0]["message"]["header"].pop("timestamp")),
    ("examples", lambda d: d["examples"][0].update(frames={"le": "54f"})),
], ids=lambda v: v if isinstance(v, str) else "")
def test_other_schemas_reject_broken_records(name, mutate):
    doc = copy.deepcopy(load(IMC / f"{name}.json"))
    assert errors(name, doc) == []
    mutate(doc)
    assert errors(name, doc), f"{name}: the broken copy was accepted"
