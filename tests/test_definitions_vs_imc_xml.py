"""vectors/imc/definitions.json against the real IMC.xml (the one imcpy 1.1.2, i.e. IMC 5.4.30, is built from).

The definitions were transcribed by hand from the seeds. Here every message, field, unit, range, flag, inline
type and enumeration/bitfield table is compared with IMC.xml. The edition ``imc-5.4.30`` must match IMC.xml exactly;
the seed edition ``imc-5.4.11`` may differ only where errata.json says so (E1, E2). Descriptions are not compared:
the seeds re-flow the text. Each test collects every difference and prints them all.
"""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from dataclasses import dataclass

import pytest

from imc_conformance.suites.imc.corpus.invalid import HIGHEST_IMC_ID, UNUSED_ID
from imc_conformance.suites.imc.imc_xml import fetch_imc_xml, parse_imc_xml
from imc_conformance.suites.imc.paths import imc_data

XML_EDITION = "imc-5.4.30"  # the IMC version of imcpy 1.1.2's IMC.xml
SEED_EDITION = "imc-5.4.11"
# The id ranges the seeds cover (imc-wire.md "Versions in play": networking 150-188, acoustic 200-216).
SEED_RANGES = (range(150, 189), range(200, 217))
UNIT_OF_KIND = {"enum": "Enumerated", "bitfield": "Bitfield"}

DEFS = json.loads(imc_data("definitions.json").read_text(encoding="utf-8"))
ERRATA = json.loads(imc_data("errata.json").read_text(encoding="utf-8"))["errata"]
OURS = {m["id"]: m for m in DEFS["messages"]}


@dataclass(frozen=True)
class Table:
    """An enumeration or bitfield table, reduced to what both sources state."""

    kind: str  # "enum" | "bitfield"
    prefix: str | None
    definition: str | None  # name of a global <def> (enum-def / bitfield-def)
    values: dict[int, tuple[str, str | None]]  # value -> (abbrev, name)


@pytest.fixture(scope="module")
def xml() -> ET.Element:
    root = parse_imc_xml(fetch_imc_xml())
    assert root.tag == "messages" and root.get("version") == XML_EDITION.removeprefix("imc-"), root.attrib
    return root


@pytest.fixture(scope="module")
def xml_messages(xml) -> dict[int, ET.Element]:
    return {int(m.get("id")): m for m in xml.findall("message")}


@pytest.fixture(scope="module")
def xml_groups(xml) -> dict[str, list[str]]:
    return {g.get("abbrev"): [t.get("abbrev") for t in g.findall("message-type")]
            for g in xml.find("message-groups").findall("message-group")}


def report(differences: list[str], what: str) -> str:
    return f"{len(differences)} {what} between definitions.json and IMC.xml:\n  " + "\n  ".join(differences)


def xml_table(xml: ET.Element, field: ET.Element) -> Table | None:
    unit = field.get("unit")
    if unit not in UNIT_OF_KIND.values():
        return None
    kind = "enum" if unit == "Enumerated" else "bitfield"
    definition = field.get("enum-def") or field.get("bitfield-def")
    source, prefix = field, field.get("prefix")
    if definition:
        section = xml.find("enumerations" if kind == "enum" else "bitfields")
        source = next(d for d in section.findall("def") if d.get("abbrev") == definition)
        prefix = prefix or source.get("prefix")
    values = {int(v.get("id"), 0): (v.get("abbrev"), v.get("name")) for v in source.findall("value")}
    return Table(kind, prefix, definition, values)


def our_table(field: dict, edition: str) -> Table | None:
    enum = field.get("enum")
    if enum is None:
        return None
    values = {v["value"]: (v["abbrev"], v.get("name")) for v in enum["values"]
              if edition in v.get("editions", [edition])}
    return Table(enum["kind"], enum["prefix"], enum.get("def"), values)


def table_differences(where: str, ours: Table | None, theirs: Table | None) -> list[str]:
    """Differences of two tables; a name only counts where ours gives one."""
    if ours is None or theirs is None:
        return [] if ours is theirs else [f"{where}: table ours={ours} xml={theirs}"]
    diffs = [f"{where}: {attr} ours={getattr(ours, attr)!r} xml={getattr(theirs, attr)!r}"
             for attr in ("kind", "prefix", "definition") if getattr(ours, attr) != getattr(theirs, attr)]
    for value in sorted(ours.values.keys() | theirs.values.keys()):
        mine, real = ours.values.get(value), theirs.values.get(value)
        if mine is None or real is None:
            diffs.append(f"{where}: value {value} ours={mine} xml={real}")
        elif mine[0] != real[0] or (mine[1] is not None and mine[1] != real[1]):
            diffs.append(f"{where}: value {value} ours={mine} xml={real}")
    return diffs


def xml_number(text: str | None) -> float | None:
    return None if text is None else float(text)


def xml_message_types(field: ET.Element, groups: dict[str, list[str]]) -> set[str]:
    named = field.get("message-type")
    if named is None:
        return set()
    return set(groups.get(named, [named]))  # a message group stands for its members


def seed_errata_by_field() -> dict[str, dict]:
    """Seed errata whose 'where' names exactly one field, 'Message.field'."""
    found = {}
    for e in ERRATA:
        parts = e["where"].split(".")
        if e["kind"] == "seed" and len(parts) == 2 and all(p.isidentifier() for p in parts):
            found[e["where"]] = e
    return found


def enum_fields():
    for m in DEFS["messages"]:
        for f in m["fields"]:
            if "enum" in f:
                yield m, f


def xml_field(xml_messages, message: dict, abbrev: str) -> ET.Element:
    return next(f for f in xml_messages[message["id"]].findall("field") if f.get("abbrev") == abbrev)


# --- messages ---------------------------------------------------------------------------------------------------

def test_every_message_is_in_xml_with_same_abbrev_and_name(xml_messages):
    diffs = []
    for mid, m in OURS.items():
        x = xml_messages.get(mid)
        if x is None:
            diffs.append(f"{m['abbrev']} ({mid}): no message with this id in IMC.xml")
            continue
        for attr in ("abbrev", "name"):
            if m[attr] != x.get(attr):
                diffs.append(f"{m['abbrev']} ({mid}): {attr} ours={m[attr]!r} xml={x.get(attr)!r}")
    assert not diffs, report(diffs, "message identity differences")


def test_message_flags_match_xml(xml_messages):
    diffs = []
    for mid, m in OURS.items():
        ours = set((m.get("flags") or {}).get("values", []))
        theirs = {f.strip() for f in (xml_messages[mid].get("flags") or "").split(",") if f.strip()}
        if ours != theirs:
            diffs.append(f"{m['abbrev']}: flags ours={sorted(ours)} xml={sorted(theirs)}")
    assert not diffs, report(diffs, "flag differences")


def test_fields_match_xml_in_order_name_type_unit_range_and_inline_type(xml_messages, xml_groups):
    diffs, compared = [], 0
    for mid, m in OURS.items():
        theirs = xml_messages[mid].findall("field")
        ours_abbrevs, their_abbrevs = [f["abbrev"] for f in m["fields"]], [f.get("abbrev") for f in theirs]
        if ours_abbrevs != their_abbrevs:
            diffs.append(f"{m['abbrev']}: fields ours={ours_abbrevs} xml={their_abbrevs}")
            continue
        for f, x in zip(m["fields"], theirs):
            where = f"{m['abbrev']}.{f['abbrev']}"
            compared += 1
            expected_unit = UNIT_OF_KIND[f["enum"]["kind"]] if "enum" in f else f.get("unit")
            pairs = {"name": (f["name"], x.get("name")), "type": (f["type"], x.get("type")),
                     "unit": (expected_unit, x.get("unit"))}
            diffs += [f"{where}: {attr} ours={a!r} xml={b!r}" for attr, (a, b) in pairs.items() if a != b]
            for attr in ("min", "max"):
                if f.get(attr) != xml_number(x.get(attr)):  # both parse to the same double, or both absent
                    diffs.append(f"{where}: {attr} ours={f.get(attr)!r} xml={x.get(attr)!r}")
            ours_types = set((f.get("message_type") or {}).get("values", []))
            their_types = xml_message_types(x, xml_groups)
            if ours_types != their_types:
                diffs.append(f"{where}: message_type ours={sorted(ours_types)} xml={sorted(their_types)} "
                             f"(IMC.xml: {x.get('message-type')!r})")
            if x.get("value") is not None:  # a constant field: the definitions cannot express it
                diffs.append(f"{where}: IMC.xml fixes the value to {x.get('value')!r}")
    assert not diffs, report(diffs, "field differences")
    assert compared == sum(len(m["fields"]) for m in OURS.values())


# --- enumerations and bitfields ---------------------------------------------------------------------------------

def test_enum_and_bitfield_tables_match_xml_exactly_in_edition_5_4_30(xml, xml_messages):
    diffs, values = [], 0
    for m, f in enum_fields():
        where = f"{m['abbrev']}.{f['abbrev']}"
        theirs = xml_table(xml, xml_field(xml_messages, m, f["abbrev"]))
        ours = our_table(f, XML_EDITION)
        values += len(ours.values)
        diffs += table_differences(where, ours, theirs)
    # Every field IMC.xml gives a table has one here, too.
    for mid, m in OURS.items():
        ours_by_abbrev = {f["abbrev"]: f for f in m["fields"]}
        for x in xml_messages[mid].findall("field"):
            if xml_table(xml, x) is not None and "enum" not in ours_by_abbrev.get(x.get("abbrev"), {}):
                diffs.append(f"{m['abbrev']}.{x.get('abbrev')}: IMC.xml has a table, definitions.json none")
    assert values > 0
    assert not diffs, report(diffs, f"table differences in edition {XML_EDITION}")


def test_seed_only_values_are_absent_from_xml_and_named_by_an_erratum(xml, xml_messages):
    errata = seed_errata_by_field()
    problems, seen = [], 0
    for m, f in enum_fields():
        where = f"{m['abbrev']}.{f['abbrev']}"
        theirs = xml_table(xml, xml_field(xml_messages, m, f["abbrev"]))
        for v in f["enum"]["values"]:
            if v.get("editions") != [SEED_EDITION]:
                continue
            seen += 1
            if v["value"] in theirs.values:
                problems.append(f"{where}: seed-only value {v['value']} {v['abbrev']} is in IMC.xml "
                                f"as {theirs.values[v['value']]}")
            erratum = errata.get(where)
            if erratum is None:
                problems.append(f"{where}: seed-only value {v['value']} {v['abbrev']} but no erratum names {where}")
            elif v.get("erratum", erratum["id"]) != erratum["id"]:
                problems.append(f"{where}: value {v['value']} names erratum {v['erratum']}, errata.json says "
                                f"{erratum['id']}")
    assert seen > 0, "expected at least the E1 value UNSUPPORTED = 666"
    assert not problems, report(problems, "seed-only value problems")


def test_seed_edition_differs_from_xml_exactly_where_errata_say(xml, xml_messages):
    """imc-5.4.11 (the seeds) vs IMC.xml: a table differs iff a seed erratum names its field (E1, E2)."""
    errata = seed_errata_by_field()
    table_fields = {f"{m['abbrev']}.{f['abbrev']}" for m, f in enum_fields()}
    named = {where for where in errata if where in table_fields}
    assert {errata[where]["id"] for where in named} == {"E1", "E2"}
    unexplained, differing, citations = [], set(), []
    for m, f in enum_fields():
        where = f"{m['abbrev']}.{f['abbrev']}"
        found = table_differences(where, our_table(f, SEED_EDITION),
                                  xml_table(xml, xml_field(xml_messages, m, f["abbrev"])))
        if found:
            differing.add(where)
        if found and where not in named:
            unexplained += found
        for v in f["enum"]["values"]:  # a value limited to some editions cites the erratum that limits it
            cited = {v.get("erratum"), v.get("source", "").removeprefix("imc-wire#")}
            if "editions" in v and (where not in named or errata[where]["id"] not in cited):
                citations.append(f"{where}: value {v['value']} {v['abbrev']} is edition-specific but cites {cited}")
    assert not unexplained, report(unexplained, f"{SEED_EDITION} differences that no erratum explains")
    assert not citations, "\n".join(citations)
    assert differing == named, f"errata name {sorted(named - differing)}, but their {SEED_EDITION} table equals IMC.xml"


# --- message ids ------------------------------------------------------------------------------------------------

def test_omitted_messages_exist_in_xml_and_not_in_definitions(xml_messages):
    omitted = {mid for e in ERRATA for mid in e.get("omitted_messages", [])}
    assert omitted == {155, 182, 207}
    for mid in omitted:
        assert mid in xml_messages, f"erratum lists {mid} as omitted, but IMC.xml has no such message"
        assert mid not in OURS, f"{mid} is listed as omitted but definitions.json defines it"


def test_xml_messages_in_the_seed_ranges_are_defined_or_documented_omissions(xml_messages):
    omitted = {mid for e in ERRATA for mid in e.get("omitted_messages", [])}
    missing = [f"{mid} {xml_messages[mid].get('abbrev')}" for mid in sorted(xml_messages)
               if any(mid in r for r in SEED_RANGES) and mid not in OURS and mid not in omitted]
    assert not missing, ("IMC.xml messages inside the seeds' id ranges that definitions.json neither defines nor "
                         f"errata.json lists as omitted: {missing}")


def test_no_xml_message_id_above_highest_imc_id(xml, xml_messages):
    # The generator relies on it: ids above HIGHEST_IMC_ID stand for "certainly unknown" (erratum I1).
    above = {mid: m.get("abbrev") for mid, m in xml_messages.items() if mid > HIGHEST_IMC_ID}
    assert not above, f"IMC.xml ids above HIGHEST_IMC_ID={HIGHEST_IMC_ID}: {above}"
    assert len(xml.findall("message")) == len(xml_messages) > 300  # ids are unique; the whole file was read


def test_ids_elsewhere_are_exactly_the_xml_messages_the_definitions_lack(xml_messages):
    """The fuzzer leaves a frame carrying one of these unjudged: a receiver of the whole protocol decodes it."""
    assert DEFS["frame"]["ids_elsewhere"]["values"] == sorted(set(xml_messages) - set(OURS))


def test_unknown_id_999_is_unused_in_xml(xml_messages):
    assert UNUSED_ID == 999
    assert UNUSED_ID not in xml_messages, f"IMC.xml defines {UNUSED_ID}: {xml_messages[UNUSED_ID].get('abbrev')}"


# --- frame ------------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("part", ["header", "footer"])
def test_frame_fields_match_xml(xml, part):
    ours = [(f["abbrev"], f["type"]) for f in DEFS["frame"][part]]
    theirs = [(f.get("abbrev"), f.get("type")) for f in xml.find(part).findall("field")]
    assert ours == theirs, f"frame {part} (abbrev, type) ours={ours} xml={theirs}"


def test_sync_number_matches_xml(xml):
    sync = next(f for f in xml.find("header").findall("field") if f.get("abbrev") == "sync")
    assert int(sync.get("value"), 16) == DEFS["frame"]["sync"]["value"] == 0xFE54


def test_type_sizes_match_xml(xml):
    theirs = {t.get("name"): t.get("size") for t in xml.find("types").findall("type")}
    assert set(theirs) == set(DEFS["types"]), (sorted(theirs), sorted(DEFS["types"]))
    for name, t in DEFS["types"].items():
        assert t.get("size") == (int(theirs[name]) if theirs[name] else None), name
