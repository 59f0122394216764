"""Definitions from an IMC.xml: every message, field, unit, range, flag, enumeration and bitfield (local and
global), inline message type and message group, in the form of ``vectors/imc/definitions.json``, each item
citing its element (``imc-xml#Message.field``). Sans-IO: ``definitions_from_xml`` takes the file's bytes.

An IMC.xml is untrusted input: it is read whole only up to ``XML_LIMIT`` bytes, a document type (and so any
entity) is refused in whatever encoding the file is written, and whatever the codec could not read as IMC (a
header unlike IMC's, a duplicate id, an unknown type, a table value its field cannot hold) is an ``XmlError``
naming the element.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET

from ...limits import XML_LIMIT
from .definitions import SCALAR_FORMATS, load_definitions

HEADER = [("sync", "uint16_t"), ("mgid", "uint16_t"), ("size", "uint16_t"), ("timestamp", "fp64_t"),
          ("src", "uint16_t"), ("src_ent", "uint8_t"), ("dst", "uint16_t"), ("dst_ent", "uint8_t")]
FOOTER = [("crc16", "uint16_t")]
SIZES = {"int8_t": 1, "uint8_t": 1, "int16_t": 2, "uint16_t": 2, "int32_t": 4, "uint32_t": 4, "int64_t": 8,
         "fp32_t": 4, "fp64_t": 8}
KINDS = {"int8_t": "int", "uint8_t": "uint", "int16_t": "int", "uint16_t": "uint", "int32_t": "int",
         "uint32_t": "uint", "int64_t": "int", "fp32_t": "float", "fp64_t": "float", "plaintext": "text",
         "rawdata": "bytes", "message": "message", "message-list": "message-list"}
TABLE_UNITS = {"Enumerated": "enum", "Bitfield": "bitfield"}
FLAGS = ("periodic", "deprecated")
ABBREV = re.compile(r"[A-Za-z][A-Za-z0-9]*\Z")
FIELD_ABBREV = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
PREFIX = re.compile(r"[A-Z][A-Z0-9_]*\Z")
CONSTANT = re.compile(r"[A-Za-z0-9][A-Za-z0-9_]*\Z")  # a table value's name after its prefix (3DTRACK)
VERSION = re.compile(r"\d+\.\d+\.\d+\Z")


class XmlError(ValueError):
    """The file is not an IMC.xml the suite can read; the message names the element."""


def xml_document(raw: bytes) -> dict:
    """The definitions document of an IMC.xml's bytes, with the packaged definitions' wire facts."""
    packaged = load_definitions().raw
    return definitions_from_xml(raw, packaged["frame"], packaged["types"])


def definitions_from_xml(raw: bytes, frame: dict, types: dict) -> dict:
    """The definitions document of the IMC.xml in ``raw``. ``frame`` and ``types``: the packaged definitions'
    frame and types, whose wire facts (sizes, CRC, byte orders, defaults) the XML does not state; the XML's
    header and footer must be IMC's."""
    root = _root(raw)
    version = root.get("version") or ""
    if not VERSION.match(version):
        raise XmlError(f"<messages version={version!r}>: not an IMC version (major.minor.patch)")
    edition = f"imc-{version}"
    _check_types(root)
    tables = {kind: _global_tables(root, section, kind) for section, kind in (("enumerations", "enum"),
                                                                               ("bitfields", "bitfield"))}
    groups = {g.get("abbrev"): [t.get("abbrev") for t in g.findall("message-type")]
              for g in _section(root, "message-groups", required=False).findall("message-group")}
    messages, ids, abbrevs = [], {}, set()
    for element in root.findall("message"):
        m = _message(element, tables)
        if m["id"] in ids:
            raise XmlError(f"<message abbrev={m['abbrev']!r}>: id {m['id']} is also {ids[m['id']]}'s")
        if m["abbrev"] in abbrevs:
            raise XmlError(f"<message abbrev={m['abbrev']!r}>: a second message of that name")
        ids[m["id"]] = m["abbrev"]
        abbrevs.add(m["abbrev"])
        messages.append((m, element))
    if not messages:
        raise XmlError("<messages>: no <message> element")
    leaf = any(m["fields"] and all(f["type"] in SIZES for f in m["fields"]) for m, _ in messages)
    out = []
    for m, element in messages:
        for f, x in zip(m["fields"], element.findall("field")):
            named = x.get("message-type")
            if named is not None:
                members = groups.get(named, [named])
                unknown = [t for t in members if t not in abbrevs]
                if unknown:
                    raise XmlError(f"<message abbrev={m['abbrev']!r}> <field abbrev={f['abbrev']!r}>: message-type "
                                   f"{named!r} names {unknown[0]!r}, which is neither a message nor a message group")
                f["message_type"] = {"values": list(dict.fromkeys(members)), "source": f["clause"]}
            elif f["type"] in ("message", "message-list") and not leaf:
                raise XmlError(f"<message abbrev={m['abbrev']!r}> <field abbrev={f['abbrev']!r}>: an inline field of "
                               "any message, and no message of scalar fields that the corpus could fill it with")
        out.append(m)
    return {
        "$schema": "../schema/definitions.schema.json",
        "protocol": "IMC",
        "description": f"Generated from an IMC.xml (IMC {version}, {len(out)} messages) by imc-conformance generate "
                       "--imc-xml: every item cites its element.",
        "editions": {edition: {"description": f"IMC {version} as its IMC.xml defines it.", "source": "imc-xml#messages"}},
        "frame": _frame(root, frame),
        "types": types,
        "messages": sorted(out, key=lambda m: m["id"]),
    }


def _root(raw: bytes) -> ET.Element:
    if len(raw) > XML_LIMIT:
        raise XmlError(f"the file is over {XML_LIMIT >> 20} MB: not an IMC.xml")
    _refuse_document_type(raw)
    try:
        root = ET.fromstring(raw)
    except (ET.ParseError, ValueError) as exc:  # ValueError: an encoding expat cannot read (UTF-7)
        raise XmlError(f"not XML: {exc}") from None
    if root.tag != "messages" or root.get("name", "IMC") != "IMC":
        raise XmlError(f"<{root.tag[:40]}>: an IMC.xml's root is <messages name=\"IMC\">")
    return root


def _refuse_document_type(raw: bytes) -> None:
    """XmlError if the file declares a document type (and so may declare entities), in whatever encoding it is
    written: expat decodes it as ElementTree will, and is stopped where the declaration starts, before anything
    in it is declared or expanded."""
    from xml.parsers import expat

    def refuse(*_) -> None:
        raise XmlError("the file declares a document type (entities are refused): an IMC.xml has none")

    parser = expat.ParserCreate()
    parser.StartDoctypeDeclHandler = refuse
    try:
        parser.Parse(raw, True)
    except XmlError:
        raise
    except (expat.ExpatError, ValueError):
        pass  # not XML: ElementTree says where


def _section(root: ET.Element, tag: str, required: bool = True) -> ET.Element:
    found = root.find(tag)
    if found is None:
        if required:
            raise XmlError(f"<messages>: no <{tag}> element")
        return ET.Element(tag)
    return found


def _check_types(root: ET.Element) -> None:
    for t in _section(root, "types").findall("type"):
        name = t.get("name")
        if name not in KINDS:
            raise XmlError(f"<type name={name!r}>: not an IMC field type the codec reads")
        size = t.get("size")
        if size is not None and name in SIZES and _int(size, f"<type name={name!r}> size") != SIZES[name]:
            raise XmlError(f"<type name={name!r}>: size {size}, where IMC's is {SIZES[name]}")


def _frame(root: ET.Element, packaged: dict) -> dict:
    """The packaged frame, with the XML's header and footer (which must be IMC's) and sync number."""
    parts = {}
    for tag, layout in (("header", HEADER), ("footer", FOOTER)):
        fields = _section(root, tag).findall("field")
        got = [(f.get("abbrev"), f.get("type")) for f in fields]
        if got != layout:
            raise XmlError(f"<{tag}>: fields {got}, where the codec reads IMC's {layout}")
        parts[tag] = [{"abbrev": a, "type": t, "description": _name(f), "source": f"imc-xml#{tag}"}
                      for (a, t), f in zip(got, fields)]
    sync = _section(root, "header").find("field").get("value")
    if sync is None or _int(sync, "<header> <field abbrev='sync'> value") != packaged["sync"]["value"]:
        raise XmlError(f"<header> <field abbrev='sync'>: value {sync!r}, where the codec reads 0xFE54")
    return dict(packaged, source="imc-xml#header", header=parts["header"], footer=parts["footer"],
                sync={"value": packaged["sync"]["value"], "source": "imc-xml#header"})


def _global_tables(root: ET.Element, section: str, kind: str) -> dict[str, dict]:
    out = {}
    for d in _section(root, section, required=False).findall("def"):
        abbrev = d.get("abbrev") or ""
        where = f"<{section}> <def abbrev={abbrev!r}>"
        if not ABBREV.match(abbrev) or abbrev in out:
            raise XmlError(f"{where}: a missing, malformed or repeated abbrev")
        out[abbrev] = {"element": d, "prefix": d.get("prefix"), "where": where,
                       "source": f"imc-xml#{section}.{abbrev}"}
    return out


def _message(element: ET.Element, tables: dict) -> dict:
    abbrev = element.get("abbrev") or ""
    where = f"<message abbrev={abbrev!r}>"
    if not ABBREV.match(abbrev):
        raise XmlError(f"{where}: not a message abbreviation")
    mid = _int(element.get("id"), f"{where} id")
    if not 0 <= mid <= 65534:
        raise XmlError(f"{where}: id {mid} is outside 0..65534 (65535 is the null id)")
    clause = f"imc-xml#{abbrev}"
    fields, seen, min_payload = [], set(), 0
    for x in element.findall("field"):
        f = _field(x, abbrev, tables)
        if f["abbrev"] in seen:
            raise XmlError(f"{where} <field abbrev={f['abbrev']!r}>: a second field of that name")
        seen.add(f["abbrev"])
        min_payload += SIZES.get(f["type"], 2)  # a prefixed type's least is its 2-byte prefix
        fields.append(f)
    m = {"id": mid, "name": element.get("name") or abbrev, "abbrev": abbrev, "clause": clause,
         "min_payload": {"value": min_payload, "source": clause}, "fields": fields}
    flags = [f.strip() for f in (element.get("flags") or "").split(",") if f.strip()]
    unknown = [f for f in flags if f not in FLAGS]
    if unknown:
        raise XmlError(f"{where}: unknown flag {unknown[0]!r} (IMC's are {', '.join(FLAGS)})")
    if flags:
        m["flags"] = {"values": list(dict.fromkeys(flags)), "source": clause}
    return m


def _field(x: ET.Element, message: str, tables: dict) -> dict:
    abbrev, kind = x.get("abbrev") or "", x.get("type")
    where = f"<message abbrev={message!r}> <field abbrev={abbrev!r}>"
    if not FIELD_ABBREV.match(abbrev):
        raise XmlError(f"{where}: not a field abbreviation")
    if kind not in KINDS:
        raise XmlError(f"{where}: unknown type {kind!r}")
    clause = f"imc-xml#{message}.{abbrev}"
    f = {"name": x.get("name") or abbrev, "abbrev": abbrev, "type": kind, "clause": clause}
    unit = x.get("unit")
    table = TABLE_UNITS.get(unit)
    if unit and table is None:
        f["unit"] = unit
    for attr in ("min", "max"):
        if x.get(attr) is not None:
            if kind not in SCALAR_FORMATS:
                raise XmlError(f"{where}: {attr} on a {kind} field")
            try:
                f[attr] = float(x.get(attr))
            except ValueError:
                raise XmlError(f"{where}: {attr} {x.get(attr)!r} is not a number") from None
            if f[attr] != f[attr] or f[attr] in (float("inf"), float("-inf")):
                raise XmlError(f"{where}: {attr} {x.get(attr)!r} is not a finite number")
            if f[attr].is_integer() and abs(f[attr]) < 2 ** 53:
                f[attr] = int(f[attr]) if kind not in ("fp32_t", "fp64_t") else f[attr]
    if table is not None:
        f["enum"] = _table(x, table, kind, where, clause, tables)
    elif x.get("enum-def") or x.get("bitfield-def"):
        raise XmlError(f"{where}: a table of values on a field whose unit is {unit!r}, not Enumerated or Bitfield")
    elif x.findall("value"):  # named special values of a quantity (StateReport.altitude's 0xFFFF): noted
        f["note"] = "special values: " + ", ".join(f"{v.get('abbrev')} = {v.get('id')}" for v in x.findall("value"))
    if x.get("message-type") is not None and kind not in ("message", "message-list"):
        raise XmlError(f"{where}: message-type on a {kind} field")
    return f


def _table(x: ET.Element, kind: str, type_: str, where: str, clause: str, tables: dict) -> dict:
    if type_ not in SIZES or type_.startswith("fp"):
        raise XmlError(f"{where}: an {'enumeration' if kind == 'enum' else 'bitfield'} on a {type_} field")
    named = x.get("enum-def" if kind == "enum" else "bitfield-def")
    source, prefix, cited = x, x.get("prefix"), clause
    table = {"kind": kind}
    if named:
        found = tables[kind].get(named)
        if found is None:
            raise XmlError(f"{where}: {'enum' if kind == 'enum' else 'bitfield'}-def {named!r} is not defined")
        source, prefix, cited = found["element"], prefix or found["prefix"], found["source"]
        table["def"] = named
    if not prefix or not PREFIX.match(prefix):
        raise XmlError(f"{where}: prefix {prefix!r} is not an IMC constant prefix")
    bits = 8 * SIZES[type_]
    lo, hi = (0, (1 << bits) - 1) if type_.startswith("u") else (-(1 << (bits - 1)), (1 << (bits - 1)) - 1)
    values, seen = [], set()
    for v in source.findall("value"):
        value = _int(v.get("id"), f"{where} <value abbrev={v.get('abbrev')!r}> id")
        if not lo <= value <= hi:
            raise XmlError(f"{where} <value abbrev={v.get('abbrev')!r}>: {value} does not fit {type_}")
        if kind == "bitfield" and value < 0:
            raise XmlError(f"{where} <value abbrev={v.get('abbrev')!r}>: {value} is no set of bits")
        abbrev = v.get("abbrev") or ""
        if not CONSTANT.match(abbrev) or value in seen:
            raise XmlError(f"{where} <value abbrev={abbrev!r}>: a missing or malformed abbrev, or a repeated value")
        seen.add(value)
        values.append({"value": value, "abbrev": abbrev, **({"name": v.get("name")} if v.get("name") else {})})
    if not values:
        raise XmlError(f"{where}: an empty {'enumeration' if kind == 'enum' else 'bitfield'}")
    return {**table, "prefix": prefix, "source": cited, "values": sorted(values, key=lambda v: v["value"])}


def _int(text: str | None, where: str) -> int:
    try:
        return int(text or "", 0)
    except ValueError:
        raise XmlError(f"{where}: {text!r} is not an integer") from None


def _name(f: ET.Element) -> str:
    return f.get("name") or f.get("abbrev") or "-"
