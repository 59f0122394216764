"""``imc-conformance generate --from IMC.xml --out DIR``: a suite folder from any IMC.xml (``run --vectors DIR``)."""

from __future__ import annotations

import json
from pathlib import Path

from ...inputs import read_bytes
from ...limits import XML_LIMIT
from .corpus.build import message_files
from .definitions import parse_definitions
from .from_xml import xml_document
from .paths import imc_data


def folder_from_xml(source: Path, out: Path) -> int:
    """Write a suite folder for the IMC.xml at ``source`` into ``out``: its definitions.json, a case file for every
    message and the coverage table (``run --vectors out`` runs it); ValueError for an XML the suite cannot read."""
    doc = xml_document(read_bytes(source, XML_LIMIT))
    defs = parse_definitions(doc)
    doc.pop("$schema")
    files = {"definitions.json": json.dumps(doc, indent=1, ensure_ascii=True) + "\n"} | message_files(defs, schema=None)
    if out.resolve().is_relative_to(imc_data().resolve()):
        raise ValueError(f"{out}: inside the suite's own data folder (generate without --from rebuilds that)")
    try:
        (out / "cases").mkdir(parents=True, exist_ok=True)
        stale = [p for p in (out / "cases").glob("*.json") if f"cases/{p.name}" not in files]
        for path in stale:
            path.unlink()
        for name, text in files.items():
            (out / name).write_text(text, encoding="utf-8")
    except OSError as exc:
        raise ValueError(f"{out}: cannot write: {exc.strerror or exc}") from None
    cases = sum(len(json.loads(t)["cases"]) for n, t in files.items() if n.startswith("cases/"))
    print(f"{cases} cases for {len(defs.messages)} messages of IMC {next(iter(doc['editions']))[4:]} in {out} "
          f"({len(stale)} stale case files removed); run them with: imc-conformance run --vectors {out}")
    return 0
