"""``imc-conformance generate --from IMC.xml --out DIR``: a suite folder from any IMC.xml (``run --vectors DIR``).

The XML is untrusted and so is the folder given. A corpus too heavy to build is refused before anything is written
(``check_weight``: the bounds of ``limits``); the case files are written one message at a time (memory bounded by
one message's file, the bytes written by ``GENERATED_LIMIT``) into a staging folder inside ``DIR``, then moved into
place. ``DIR`` must be new, empty, or a folder this command wrote (its ``manifest.json`` says so), and only the files
it wrote before are replaced or removed.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
import tempfile
from pathlib import Path

import orjson

from ...inputs import read_bytes
from ...limits import CORPUS_WEIGHT_MAX, GENERATED_LIMIT, MESSAGE_WEIGHT_MAX, XML_LIMIT
from ..data_suite import MANIFEST
from .corpus.build import message_files
from .corpus.coverage import coverage_markdown
from .corpus.samples import inner_types
from .definitions import Definitions, parse_definitions
from .from_xml import xml_document
from .paths import imc_data

STAGING = ".generate-"  # the prefix of the staging folder inside --out
COVERAGE_KEYS = ("id", "expect", "rule", "tags")  # what the coverage table reads of a case
OURS = re.compile(r"definitions\.json|cases/\d+-[A-Za-z][A-Za-z0-9]*\.json")  # what generate --from writes and removes
FRAMING_WEIGHT = 64  # what a message's framing cases weigh, whatever its fields (see check_weight)


def write_case_files(defs: Definitions, folder: Path, only: frozenset[str] | None = None,
                     only_edition: str | None = None) -> tuple[dict[str, dict], str, int]:
    """Write the case file of every message of ``defs`` (``only``: of these) into ``folder/cases``, one message at a
    time; the manifest entries of the files written, the coverage table, the number of cases. ValueError, before
    anything is written, for a corpus too heavy to build (``check_weight``), and past ``GENERATED_LIMIT`` bytes."""
    chosen = [m for m in defs.suite_messages if only is None or m.abbrev in only]
    check_weight(defs, chosen)
    (folder / "cases").mkdir(parents=True, exist_ok=True)
    entries, slim, size, cases = {}, {}, 0, 0
    for mdef in chosen:
        files = message_files(defs, schema=None, only=frozenset({mdef.abbrev}), only_edition=only_edition)
        name = next(n for n in files if n.startswith("cases/"))
        data = files[name].encode()
        size += len(data)
        if size > GENERATED_LIMIT:
            raise ValueError(f"the corpus would be over {GENERATED_LIMIT >> 20} MB (at <message abbrev="
                             f"{mdef.abbrev!r}>), the most generate writes (IMC.xml 5.4.30's is 147 MB)")
        (folder / name).write_bytes(data)
        entries[name] = {"sha256": hashlib.sha256(data).hexdigest(), "group": mdef.abbrev, "kind": "vector"}
        written = orjson.loads(data)["cases"]
        slim[mdef.abbrev] = [{k: c[k] for k in COVERAGE_KEYS if k in c} for c in written]
        cases += len(written)
    return entries, coverage_markdown(defs, slim), cases


def check_weight(defs: Definitions, chosen: list) -> None:
    """ValueError for a message, or a corpus, heavier than ``limits`` lets generate build (see ``weights``)."""
    carried, total = weights(defs), 0
    for mdef in chosen:
        weight = len(mdef.fields) * carried[mdef.abbrev]
        if weight > MESSAGE_WEIGHT_MAX:
            raise ValueError(f"<message abbrev={mdef.abbrev!r}>: {len(mdef.fields)} fields and up to "
                             f"{carried[mdef.abbrev]} values in one case weigh {weight}, and a corpus is built for "
                             f"messages of at most {MESSAGE_WEIGHT_MAX} (IMC.xml 5.4.30's heaviest: 779)")
        total += weight + FRAMING_WEIGHT
    if total > CORPUS_WEIGHT_MAX:
        raise ValueError(f"{len(chosen)} messages weigh {total} (fields times the values a case carries, and "
                         f"{FRAMING_WEIGHT} a message), and a corpus is built for at most {CORPUS_WEIGHT_MAX} (IMC.xml "
                         "5.4.30: 36,896)")


def weights(defs: Definitions, depth: int = 3) -> dict[str, int]:
    """The values one case of each message may carry: its fields, and for an inline field or list the most its types
    carry, inline messages nested ``depth`` deep (the generator nests them three levels at most). Level by level,
    no recursion."""
    level = {m.abbrev: len(m.fields) for m in defs.messages}
    for _ in range(depth):
        level = {m.abbrev: len(m.fields) + sum(max(level[t.abbrev] for t in inner_types(defs, f))
                                               for f in m.fields if f.type in ("message", "message-list"))
                 for m in defs.messages}
    return level


def folder_from_xml(source: Path, out: Path) -> int:
    """Write a suite folder for the IMC.xml at ``source`` into ``out``: its definitions.json, a case file for every
    message and the coverage table (``run --vectors out`` runs it); ValueError for an XML the suite cannot read, a
    corpus over the bounds, or a folder it may not write."""
    raw = read_bytes(source, XML_LIMIT)
    doc = xml_document(raw)
    defs = parse_definitions(doc)
    doc.pop("$schema")
    if out.resolve().is_relative_to(imc_data().resolve()):
        raise ValueError(f"{out}: inside the suite's own data folder (generate without --from rebuilds that)")
    created, staging = not out.exists(), None
    try:
        before = _written_before(out)
        staging = Path(tempfile.mkdtemp(prefix=STAGING, dir=_made(out)))
        definitions = (json.dumps(doc, indent=1, ensure_ascii=True) + "\n").encode()
        (staging / "definitions.json").write_bytes(definitions)
        entries, coverage, cases = write_case_files(defs, staging)
        (staging / "coverage.md").write_text(coverage, encoding="utf-8")
        entries["definitions.json"] = {"sha256": hashlib.sha256(definitions).hexdigest()}
        manifest = {"format": 1, "description": "Written by imc-conformance generate --from: the SHA-256 of every JSON "
                                               "file it wrote. It replaces or removes only these files.",
                    "generated_from": {"file": source.name, "sha256": hashlib.sha256(raw).hexdigest()},
                    "files": dict(sorted(entries.items()))}
        (staging / MANIFEST).write_text(json.dumps(manifest, indent=1) + "\n", encoding="utf-8")
        stale = sorted(set(before) - set(entries))
        for name in stale:
            (out / name).unlink(missing_ok=True)
        for name in [*entries, "coverage.md", MANIFEST]:
            os.replace(staging / name, out / name)
    except (OSError, ValueError) as exc:
        if created:
            shutil.rmtree(out, ignore_errors=True)
        if isinstance(exc, ValueError):
            raise
        raise ValueError(f"{out}: cannot write: {exc.strerror or exc}") from None
    finally:
        if staging is not None:
            shutil.rmtree(staging, ignore_errors=True)
    print(f"{cases} cases for {len(defs.messages)} messages of IMC {next(iter(doc['editions']))[4:]} in {out} "
          f"({len(stale)} stale case files removed); run them with: imc-conformance run --vectors {out}")
    return 0


def _made(out: Path) -> Path:
    """``out`` with its ``cases`` folder, created as need be."""
    (out / "cases").mkdir(parents=True, exist_ok=True)
    return out


def _written_before(out: Path) -> list[str]:
    """The files generate --from wrote into ``out`` before (none for a new or empty folder); ValueError for a folder
    it did not write, whose files it never replaces. What an interrupted run left (its staging folder) is removed."""
    if not out.exists():
        return []
    if not out.is_dir():
        raise ValueError(f"{out}: not a folder")
    entries = list(out.iterdir())
    files = [] if all(p.name.startswith(STAGING) for p in entries) else _manifest_files(out)
    if files is None:
        raise ValueError(f"{out}: a folder generate --from did not write (it has no manifest.json of its own), whose "
                         "files it does not replace: give a new or an empty folder")
    for path in entries:
        if path.name.startswith(STAGING):
            shutil.rmtree(path, ignore_errors=True)
    return files


def _manifest_files(out: Path) -> list[str] | None:
    """The files the manifest of a folder generate --from wrote lists, or None if it has no such manifest (a manifest
    is a file anyone could have edited: a name that is not one generate writes makes it none)."""
    try:
        manifest = orjson.loads(read_bytes(out / MANIFEST))
        files = list(manifest["files"]) if "generated_from" in manifest else None
    except (ValueError, LookupError, TypeError):
        return None
    if files is None or not all(isinstance(n, str) and OURS.fullmatch(n) for n in files):
        return None
    return files
