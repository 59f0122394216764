"""Rebuild the IMC corpus: one vector file per message, the coverage table, deterministically.

``imc-conformance generate`` (or ``python -m imc_conformance.suites.imc.corpus.build``) writes
``vectors/imc/cases/*.json``, ``vectors/imc/coverage.md`` and the behavioural coverage of the live cases,
``vectors/imc/behaviour-coverage.md``; ``--check`` only reports drift.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from ....kinds.scenario.coverage import coverage_markdown as behaviour_markdown, live_cases
from ....fuzz import promote
from ....fuzz.promote import promoted_cases
from ....inputs import read_bytes
from ....limits import XML_LIMIT
from ..definitions import Definitions, lint_definitions, load_definitions, parse_definitions
from ..fuzzing import ImcFuzzSource
from ..whole import xml_document
from ... import load_suite
from ...data_suite import write_generated
from ..paths import imc_data
from .acceptable import add_acceptable
from .coverage import coverage_markdown
from .invalid import add_invalid
from .records import MessageCases
from .valid import add_valid

FORMAT_VERSION = 1


def load_examples() -> dict[str, list[dict]]:
    raw = json.loads(imc_data("examples.json").read_text(encoding="utf-8"))
    by_message: dict[str, list[dict]] = {}
    for example in raw["examples"]:
        by_message.setdefault(example["message"]["abbrev"], []).append(example)
    return by_message


def build_corpus(defs: Definitions) -> dict[str, str]:
    """File name (relative to vectors/imc) -> exact text, for every generated file."""
    examples = load_examples()
    promoted = promoted_cases(promote.read(imc_data("promoted.json"), "imc"), {
        e: ImcFuzzSource(defs, e, {r["id"]: r["clause"] for r in load_suite("imc").rules}) for e in defs.editions})
    files = message_files(defs, examples, promoted)
    statements = json.loads(imc_data("statements.json").read_text(encoding="utf-8"))["statements"]
    register = json.loads(imc_data("ambiguities.json").read_text(encoding="utf-8"))["ambiguities"]
    bounds = json.loads(imc_data("exchanges.json").read_text(encoding="utf-8"))["bounds"]
    files["behaviour-coverage.md"] = behaviour_markdown("IMC", statements, live_cases(imc_data()), register, bounds)
    return files


def message_files(defs: Definitions, examples: dict[str, list[dict]] | None = None,
                  promoted: dict[str, list[dict]] | None = None, schema: str | None = "../../schema",
                  only: frozenset[str] | None = None, only_edition: str | None = None) -> dict[str, str]:
    """The case file of every message the definitions cover (``only``: of these messages) and the coverage table
    (``examples``: realistic messages, ``promoted``: kept fuzz findings, by message; ``schema``: the schema folder
    relative to cases/, for editors, None where there is none; ``only_edition``: every case holds under that edition
    alone, as where the files join a suite of more editions)."""
    files: dict[str, str] = {}
    per_message = {}
    for mdef in defs.suite_messages:
        if only is not None and mdef.abbrev not in only:
            continue
        mc = MessageCases(defs, mdef)
        add_valid(mc, (examples or {}).get(mdef.abbrev, []))
        add_acceptable(mc)
        add_invalid(mc)
        mc.extend((promoted or {}).get(mdef.abbrev, []))
        if only_edition is not None:
            for case in mc.cases:
                expect = case["expect"]
                case["expect"] = {only_edition: expect if isinstance(expect, str) else expect[only_edition]}
        doc = {
            **({"$schema": f"{schema}/vectors.schema.json"} if schema else {}),
            "format": FORMAT_VERSION,
            "suite": "imc",
            "message": {"abbrev": mdef.abbrev, "id": mdef.id, "name": mdef.name, "clause": mdef.clause,
                        "definition": mdef.hash},
            "editions": [only_edition] if only_edition else list(defs.editions),
            "cases": mc.cases,
        }
        per_message[mdef.abbrev] = mc.cases
        files[f"cases/{mdef.id:03d}-{mdef.abbrev}.json"] = json.dumps(doc, indent=1, ensure_ascii=True) + "\n"
    files["coverage.md"] = coverage_markdown(defs, per_message)
    return files


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


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="imc-conformance generate", description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="report files that differ from a fresh build; write nothing")
    args = parser.parse_args(argv)
    defs = load_definitions()
    for problem in lint_definitions(defs):  # reported, never "fixed": such values become acceptable encode cases
        print(f"definitions: {problem}")
    files = build_corpus(defs)
    return write_generated(load_suite("imc"), files, args.check, "vectors/imc")


if __name__ == "__main__":
    sys.exit(main())
