"""The whole protocol: every message of an IMC.xml (by default the one imcpy ships), as a suite folder.

The seed messages keep everything the seeds give them (definitions with both editions, their corpus, clauses and
errata, the live cases); every other message of the XML is added with its XML definition and a generated corpus
that cites its element and holds only for the XML's edition (what another edition made of it is not known). The
folder is built once per IMC.xml and package version into the cache and written with a manifest like the packaged
folder's, so a run trusts its files by their hashes and reads only the selected messages' files.
"""

from __future__ import annotations

import hashlib
import json
from functools import cache
from pathlib import Path

from ...inputs import read_bytes
from ...limits import XML_LIMIT
from ..data_suite import MANIFEST, manifest_entries
from .definitions import Definitions, parse_definitions
from .from_xml import XmlError, xml_document
from .paths import IMC


def generator_sources() -> list[bytes]:
    """The source of the code that builds the folder: a change to it makes every cached folder stale."""
    here = Path(__file__).parent
    return [p.read_bytes() for p in (here / "whole.py", here / "from_xml.py", here / "codec.py", here / "definitions.py",
                                     *sorted((here / "corpus").glob("*.py")))]


@cache
def imc_xml_definitions() -> Definitions:
    """Every message of the IMC.xml imcpy ships (fetched once into the cache) as definitions."""
    from .imc_xml import fetch_imc_xml

    return parse_definitions(xml_document(read_bytes(fetch_imc_xml(), XML_LIMIT)))


def merged_document(seed: dict, xml: dict) -> dict:
    """The seed definitions with every message of the XML they lack; the seeds' auxiliary messages become suite
    messages. XmlError where the XML gives a seed message's id another name."""
    by_id = {m["id"]: m for m in xml["messages"]}
    messages = []
    for m in seed["messages"]:
        theirs = by_id.pop(m["id"], None)
        if theirs is not None and theirs["abbrev"] != m["abbrev"]:
            raise XmlError(f"<message abbrev={theirs['abbrev']!r}>: id {m['id']} is the seeds' {m['abbrev']}")
        messages.append({k: v for k, v in m.items() if k != "auxiliary"})
    messages.extend(by_id.values())
    frame = {k: v for k, v in seed["frame"].items() if k != "ids_elsewhere"}
    version = next(iter(xml["editions"]))[4:]
    return {**seed, "description": f"{seed['description']} With every other message of IMC.xml {version} "
                                   f"({len(messages)} messages in all), each citing its element.",
            "frame": frame, "messages": sorted(messages, key=lambda m: m["id"])}


def whole_files(seed_folder: Path, xml_raw: bytes) -> dict[str, bytes]:
    """Every file of the whole-protocol folder (relative path -> bytes), but its manifest."""
    from .corpus.build import message_files

    seed_doc = json.loads(read_bytes(seed_folder / "definitions.json"))
    xml = xml_document(xml_raw)
    edition = next(iter(xml["editions"]))
    merged = merged_document(seed_doc, xml)
    seed_ids = {m["id"] for m in seed_doc["messages"] if not m.get("auxiliary")}
    generated = message_files(parse_definitions(xml), schema=None,
                              only=frozenset(m["abbrev"] for m in xml["messages"] if m["id"] not in seed_ids),
                              only_edition=edition)
    files = {p.relative_to(seed_folder).as_posix(): p.read_bytes() for p in sorted(seed_folder.rglob("*"))
             if p.is_file() and p.name not in (MANIFEST, "definitions.json")}
    files["definitions.json"] = (json.dumps(merged, indent=1, ensure_ascii=True) + "\n").encode()
    files["coverage-generated.md"] = generated.pop("coverage.md").encode()
    files.update((name, text.encode()) for name, text in generated.items())
    return files


def whole_folder() -> Path:
    """The whole-protocol folder of the IMC.xml imcpy ships, built into the cache the first time (and the folders
    built before for another XML or another version of the suite removed)."""
    from ...cache import cache_dir
    from .imc_xml import fetch_imc_xml

    xml_raw = read_bytes(fetch_imc_xml(), XML_LIMIT)
    key = hashlib.sha256(b"".join([xml_raw, read_bytes(IMC / MANIFEST), *generator_sources()])).hexdigest()[:16]
    target = cache_dir() / f"imc-whole-{key}"
    if (target / MANIFEST).exists():
        return target
    import os
    import shutil
    import tempfile

    files = whole_files(IMC, xml_raw)
    partial = Path(tempfile.mkdtemp(prefix=target.name + ".", dir=target.parent))
    try:
        for name, data in files.items():
            (partial / name).parent.mkdir(parents=True, exist_ok=True)
            (partial / name).write_bytes(data)
        from .suite import ImcSuite

        entries = manifest_entries(files, ImcSuite.case_folders, ImcSuite.group_of)
        (partial / MANIFEST).write_text(json.dumps({"format": 1, "description": "Written by imc-conformance for the "
                                                    "whole protocol: the SHA-256 of every JSON file as built.",
                                                    "files": entries}, indent=1) + "\n", encoding="utf-8")
        try:
            os.rename(partial, target)
        except OSError:  # another process built it first
            if not (target / MANIFEST).exists():
                raise
    finally:
        shutil.rmtree(partial, ignore_errors=True)
    for stale in target.parent.glob("imc-whole-*"):  # built for another IMC.xml or another version: 140 MB each
        if stale != target and "." not in stale.name:
            shutil.rmtree(stale, ignore_errors=True)
    return target
