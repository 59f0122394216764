"""The whole protocol: every message of an IMC.xml (by default the one imcpy ships), as a suite folder.

The seed messages keep everything the seeds give them (definitions with both editions, their corpus, clauses and
errata, the live cases); every other message of the XML is added with its XML definition and a generated corpus
that cites its element and holds only for the XML's edition (what another edition made of it is not known). The
folder is built once per IMC.xml and package version into the cache and written with a sealed manifest, so a run
trusts its files by their hashes, reads only the selected messages' files, and never uses a file not as built.
"""

from __future__ import annotations

import fcntl
import hashlib
import json
import os
import shutil
import tempfile
import time
from functools import cache
from pathlib import Path

import orjson

from ... import __version__
from ...inputs import read_bytes
from ...limits import XML_LIMIT
from ..data_suite import MANIFEST, manifest_entries
from .definitions import Definitions, parse_definitions
from .from_xml import XmlError, xml_document
from .paths import IMC
from .xml_folder import write_case_files

PREFIX = "imc-whole-"
KEEP = 3  # whole-protocol folders kept in the cache: the one in use and the two used last before it (143 MB each)


def generator_sources() -> list[bytes]:
    """The source of the code that builds the folder: a change to it makes every cached folder stale."""
    here = Path(__file__).parent
    return [p.read_bytes() for p in (here / "whole.py", here / "xml_folder.py", here / "from_xml.py", here / "codec.py",
                                     here / "definitions.py", *sorted((here / "corpus").glob("*.py")))]


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


def write_folder(folder: Path, xml_raw: bytes) -> dict[str, dict]:
    """Write every file of the whole-protocol folder into ``folder`` (the seed folder's files, the merged
    definitions, a case file for every other message, one at a time) and return its manifest entries."""
    from .suite import ImcSuite

    seed_doc = json.loads(read_bytes(IMC / "definitions.json"))
    xml = xml_document(xml_raw)
    edition = next(iter(xml["editions"]))
    files = {p.relative_to(IMC).as_posix(): p.read_bytes() for p in sorted(IMC.rglob("*"))
             if p.is_file() and p.name not in (MANIFEST, "definitions.json")}
    files["definitions.json"] = (json.dumps(merged_document(seed_doc, xml), indent=1, ensure_ascii=True) + "\n").encode()
    for name, data in files.items():
        (folder / name).parent.mkdir(parents=True, exist_ok=True)
        (folder / name).write_bytes(data)
    seed_ids = {m["id"] for m in seed_doc["messages"] if not m.get("auxiliary")}
    generated, coverage, _ = write_case_files(
        parse_definitions(xml), folder, only=frozenset(m["abbrev"] for m in xml["messages"] if m["id"] not in seed_ids),
        only_edition=edition)
    (folder / "coverage-generated.md").write_text(coverage, encoding="utf-8")
    return manifest_entries(files, ImcSuite.case_folders, ImcSuite.group_of) | generated


def whole_folder() -> Path:
    """The whole-protocol folder of the IMC.xml imcpy ships, for this version of the suite: built into the cache the
    first time, and again when it is damaged (no manifest, a file it lists missing); held (a shared lock) while this
    process lives, so that no other process removes it. Folders of other XMLs or versions are kept while among the
    ``KEEP`` used last (two versions sharing a cache do not rebuild in turn), and removed after, unless in use."""
    from ...cache import cache_dir
    from .imc_xml import fetch_imc_xml

    xml_raw = read_bytes(fetch_imc_xml(), XML_LIMIT)
    key = hashlib.sha256(b"".join([__version__.encode(), xml_raw, read_bytes(IMC / MANIFEST),
                                   *generator_sources()])).hexdigest()[:16]
    target = cache_dir() / f"{PREFIX}{key}"
    _hold(target)
    if not _complete(target):
        _build(target, xml_raw)
    _prune(target)
    return target


def _complete(folder: Path) -> bool:
    """Whether the folder has its manifest and every file the manifest lists (their bytes are checked when read)."""
    try:
        files = orjson.loads(read_bytes(folder / MANIFEST))["files"]
        return all((folder / name).is_file() for name in files)
    except (ValueError, LookupError, TypeError):
        return False


def _build(target: Path, xml_raw: bytes) -> None:
    """Build the folder beside ``target`` and move it into place (a damaged one there is moved aside first); another
    process's build that lands first is kept."""
    partial = Path(tempfile.mkdtemp(prefix=f"{target.name}.", dir=target.parent))
    try:
        entries = write_folder(partial, xml_raw)
        (partial / MANIFEST).write_text(json.dumps({
            "format": 1, "description": "Written by imc-conformance for the whole protocol: the SHA-256 of every JSON "
                                        "file as built. Sealed: a file not as built makes the folder damaged (refused, "
                                        "then rebuilt), never used.",
            "sealed": True, "files": entries}, indent=1) + "\n", encoding="utf-8")
        try:
            os.rename(partial, target)
        except OSError:
            if _complete(target):  # another process built it first
                return
            aside = Path(tempfile.mkdtemp(prefix=f"{target.name}.", dir=target.parent))
            os.rename(target, aside / "damaged")
            os.rename(partial, target)
            shutil.rmtree(aside, ignore_errors=True)
    finally:
        shutil.rmtree(partial, ignore_errors=True)


_HELD: dict = {}  # folder -> its lock file, open (and so locked) while this process lives


def _hold(folder: Path) -> None:
    """Take a shared lock on the folder's lock file for the life of this process, and mark the folder used now."""
    if folder not in _HELD:
        _HELD[folder] = open(_lock_path(folder), "a+b")
        fcntl.flock(_HELD[folder], fcntl.LOCK_SH)
    os.utime(_HELD[folder].fileno())


def _prune(current: Path) -> None:
    """Remove the folders of other XMLs or versions beyond the ``KEEP`` used last, unless a process holds them; and
    what interrupted builds left (older than a day). Best effort: what cannot be removed now is removed later."""
    root = current.parent
    others = [p for p in root.glob(f"{PREFIX}*") if p.is_dir() and "." not in p.name and p != current]
    others.sort(key=_last_used, reverse=True)
    for stale in others[KEEP - 1:]:
        aside = _move_aside(stale)
        if aside is not None:
            shutil.rmtree(aside, ignore_errors=True)
    for left in root.glob(f"{PREFIX}*.*"):
        try:
            if left.is_dir() and time.time() - left.stat().st_mtime > 86400:
                shutil.rmtree(left, ignore_errors=True)
        except OSError:
            pass


def _move_aside(folder: Path) -> Path | None:
    """The folder moved into a new folder beside it (to be removed), under its lock taken exclusively; None if a
    process holds it or it cannot be moved."""
    try:
        with open(_lock_path(folder), "a+b") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
            aside = Path(tempfile.mkdtemp(prefix=f"{folder.name}.", dir=folder.parent))
            os.rename(folder, aside / "stale")
            return aside
    except OSError:  # held (BlockingIOError), or gone already
        return None


def _lock_path(folder: Path) -> Path:
    return folder.with_name(folder.name + ".lock")


def _last_used(folder: Path) -> float:
    """When a process last took the folder (its lock file's time), else when it was built."""
    for path in (_lock_path(folder), folder):
        try:
            return path.stat().st_mtime
        except OSError:
            pass
    return 0.0
