"""Rebuild the IMC corpus: one vector file per message, the coverage table, deterministically.

``imc-conformance generate`` (or ``python -m imc_conformance.suites.imc.corpus.build``) writes
``vectors/imc/cases/*.json``, ``vectors/imc/coverage.md``, the provenance of every rule and class
(``vectors/imc/provenance.md``) and the behavioural coverage of the live cases, ``vectors/imc/behaviour-coverage.md``;
``--check`` only reports drift. Both first prove the corpus: the lint of its rules' sources and the one-flaw oracle
(``oracle.py``); a corpus that fails them is not written.
"""

from __future__ import annotations

import argparse
import json
import sys

from ....errors import CorpusError
from ....kinds.scenario.coverage import audit_problem, coverage_markdown as behaviour_markdown, live_cases
from ....fuzz import promote
from ....fuzz.promote import promoted_cases
from ....kinds.vector.provenance import case_documents, proven, provenance_markdown
from ..definitions import Definitions, lint_definitions, load_definitions
from ..fuzzing import ImcFuzzSource
from ... import load_suite
from ...data_suite import write_generated
from ..paths import imc_data
from .acceptable import add_acceptable
from .coverage import coverage_markdown
from .invalid import add_invalid
from .oracle import corpus_problems
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
    files["provenance.md"] = provenance_markdown("IMC", rules_document(), case_documents(files))
    document = json.loads(imc_data("statements.json").read_text(encoding="utf-8"))
    statements, audit, live = document["statements"], document.get("audit"), live_cases(imc_data())
    problem = audit_problem(statements, audit, live)
    if problem:
        raise CorpusError(f"{imc_data('statements.json')}: .audit: {problem}")
    register = json.loads(imc_data("ambiguities.json").read_text(encoding="utf-8"))["ambiguities"]
    bounds = json.loads(imc_data("exchanges.json").read_text(encoding="utf-8"))["bounds"]
    files["behaviour-coverage.md"] = behaviour_markdown("IMC", statements, live, register, bounds, audit)
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


def rules_document() -> dict:
    return json.loads(imc_data("rules.json").read_text(encoding="utf-8"))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="imc-conformance generate", description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="report files that differ from a fresh build; write nothing")
    args = parser.parse_args(argv)
    defs = load_definitions()
    for problem in lint_definitions(defs):  # reported, never "fixed": such values become acceptable encode cases
        print(f"definitions: {problem}")
    files = build_corpus(defs)
    if not proven(rules_document(), files, lambda documents: corpus_problems(defs, documents)):
        return 1  # a corpus the lint or the oracle refuses is not written
    return write_generated(load_suite("imc"), files, args.check, "vectors/imc")


if __name__ == "__main__":
    sys.exit(main())
