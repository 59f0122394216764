"""Hardening of the newer surfaces (issue 33): generate --from, the whole protocol's cache, fuzz, shards and saved
results, the command line's bounds. Each test is one way a hostile or careless user got a wrong verdict, lost data,
a hang or a traceback; its docstring says which item of the issue."""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

from test_imc_xml_folder import MESSAGES, TABLES, definitions, imc_xml

from imc_conformance.cli import main
from imc_conformance.errors import CorpusError
from imc_conformance.paths import VECTORS
from imc_conformance.suites.imc.from_xml import XmlError


def one_line(err: str, says: str) -> None:
    assert says in err and err.count("\n") == 1 and "Traceback" not in err, err


def refused(capsys, argv: list[str], says: str) -> None:
    """The command line refuses ``argv`` as argparse does (its usage, then one line saying why), no traceback."""
    with pytest.raises(SystemExit) as stop:
        main(argv)
    err = capsys.readouterr().err
    assert stop.value.code == 2 and err.splitlines()[-1].endswith(says) and "Traceback" not in err, err


def tree(folder: Path) -> dict[str, str]:
    return {p.relative_to(folder).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def generate(tmp_path: Path, raw: bytes, out: Path) -> int:
    source = tmp_path / "IMC.xml"
    source.write_bytes(raw)
    return main(["generate", "--from", str(source), "--out", str(out)])


# ---------------------------------------------------------------- generate --from

@pytest.mark.parametrize("codec,declared", [("utf-16", "UTF-16"), ("utf-16-be", "UTF-16"), ("utf-16-le", "UTF-16"),
                                           ("utf-8-sig", "UTF-8"), ("latin-1", "ISO-8859-1")])
def test_1_a_document_type_is_refused_in_whatever_encoding_the_xml_is_written(tmp_path, capsys, codec, declared):
    """Item 1: the refusal searched the raw bytes for ASCII ``<!DOCTYPE``; in UTF-16 expat then expanded an
    internal entity into the definitions and the case files."""
    text = imc_xml(MESSAGES.replace('name="Entity State"', 'name="&evil;"')).decode()
    text = text.replace('<?xml version="1.0"?>', f'<?xml version="1.0" encoding="{declared}"?>'
                        '<!DOCTYPE messages [<!ENTITY evil "EXPANDED">]>')
    raw = text.encode(codec)
    with pytest.raises(XmlError, match="declares a document type"):
        definitions(raw)
    assert generate(tmp_path, raw, tmp_path / "out") == 2
    one_line(capsys.readouterr().err, "declares a document type")
    assert not (tmp_path / "out").exists()


def test_2_generate_from_never_replaces_a_folder_it_did_not_write_and_removes_only_what_it_wrote(tmp_path, capsys):
    """Item 2: pointed at a copy of vectors/ros_acomms, generate --from removed every case file and overwrote its
    definitions.json."""
    theirs = tmp_path / "ros_acomms"
    shutil.copytree(VECTORS / "ros_acomms", theirs)
    before = tree(theirs)
    assert generate(tmp_path, imc_xml(), theirs) == 2
    one_line(capsys.readouterr().err, "a folder generate --from did not write")
    assert tree(theirs) == before
    ours = tmp_path / "ours"
    assert generate(tmp_path, imc_xml(), ours) == 0
    (ours / "cases" / "mine.json").write_text("{}")  # the user's own files are never touched
    (ours / "notes.txt").write_text("kept")
    holder = ours / "cases" / "002-Holder.json"
    assert holder.exists()
    entity_state_only = MESSAGES.split('<message id="2"')[0]
    assert generate(tmp_path, imc_xml(entity_state_only, tables=TABLES.split("<message-groups>")[0]), ours) == 0
    assert "(1 stale case files removed)" in capsys.readouterr().out
    assert not holder.exists() and (ours / "cases" / "mine.json").read_text() == "{}"
    assert (ours / "notes.txt").read_text() == "kept" and not list(ours.glob(".generate-*"))


def wide(fields: int, kind: str = "uint8_t") -> str:
    return ('<message id="7" name="Wide" abbrev="Wide">'
            + "".join(f'<field name="F{i}" abbrev="f{i}" type="{kind}"/>' for i in range(fields)) + "</message>")


@pytest.mark.parametrize("messages,says", [
    (wide(2000), "<message abbrev='Wide'>: 2000 fields and up to 2000 values in one case weigh 4000000"),
    ("".join(f'<message id="{i}" name="M{i}" abbrev="M{i}"><field name="A" abbrev="a" type="uint8_t"/></message>'
             for i in range(1, 3001)), "3000 messages weigh 195000"),
    ('<message id="1" name="Inner" abbrev="Inner">' + "".join(
        f'<field name="F{i}" abbrev="f{i}" type="fp64_t"/>' for i in range(64)) + '</message><message id="2" '
     'name="Outer" abbrev="Outer">' + "".join(f'<field name="L{i}" abbrev="l{i}" type="message-list" '
                                              f'message-type="Inner"/>' for i in range(64)) + "</message>",
     "<message abbrev='Outer'>: 64 fields and up to 4160 values in one case weigh 266240"),
])
def test_3_an_xml_whose_corpus_would_be_too_large_is_refused_in_one_line_before_anything_is_written(
        tmp_path, capsys, messages, says):
    """Item 3: 3,000 one-field messages (310 KB of XML) ended in a MemoryError; one message of 2,000 uint8 fields
    did not finish in 100 s. A corpus grows with its messages' fields times the values a case carries: over the
    bounds of ``limits`` it is refused at once."""
    assert generate(tmp_path, imc_xml(messages, tables=""), tmp_path / "out") == 2
    one_line(capsys.readouterr().err, says)
    assert not (tmp_path / "out").exists()


def test_3_the_case_files_are_written_one_message_at_a_time_and_bounded_in_bytes(tmp_path, capsys, monkeypatch):
    from imc_conformance.suites.imc import xml_folder

    seen = []
    real = xml_folder.message_files
    monkeypatch.setattr(xml_folder, "message_files", lambda defs, **kw: seen.append(kw["only"]) or real(defs, **kw))
    assert generate(tmp_path, imc_xml(), tmp_path / "out") == 0
    assert seen == [frozenset({"EntityState"}), frozenset({"Holder"})]  # never two messages' cases in memory
    monkeypatch.setattr(xml_folder, "GENERATED_LIMIT", 10_000)
    assert generate(tmp_path, imc_xml(), tmp_path / "small") == 2
    one_line(capsys.readouterr().err, "the corpus would be over 0 MB (at <message abbrev=")
    assert not (tmp_path / "small").exists()


def test_4_fields_named_abbrev_fields_and_header_are_fields(tmp_path, capsys):
    """Item 4: fields named ``abbrev`` and ``fields`` were mistaken for an inline message (TypeError)."""
    from imc_conformance.core.runner import run_cases
    from imc_conformance.core.verdicts import Verdict
    from imc_conformance.files import open_corpus
    from imc_conformance.sessions.library import LibrarySession
    from imc_conformance.suites.imc.mutants import Reference

    odd = ('<message id="5" name="Odd" abbrev="Odd"><field name="A" abbrev="abbrev" type="uint8_t"/>'
           '<field name="F" abbrev="fields" type="uint8_t"/>'
           '<field name="H" abbrev="header" type="message" message-type="EntityState"/></message>')
    assert generate(tmp_path, imc_xml(MESSAGES + odd), tmp_path / "out") == 0
    suite, cases = open_corpus("imc", tmp_path / "out")
    result = run_cases(LibrarySession(Reference(suite.defs), "reference"), suite, cases, edition="imc-9.1.0",
                       adapter="reference")
    assert {c.verdict for c in result.cases} <= {Verdict.PASS, Verdict.IMPL_DEFINED}
    assert any(c.id.startswith("imc/Odd/") for c in result.cases)


def test_4_an_inline_field_of_any_message_with_no_message_of_scalars_to_fill_it_is_one_line(tmp_path, capsys):
    """Found beside item 4: the generator fills an inline field of no declared type with a message of scalar fields;
    an XML with none was a StopIteration traceback."""
    raw = imc_xml('<message id="5" name="Odd" abbrev="Odd"><field name="T" abbrev="t" type="plaintext"/>'
                  '<field name="H" abbrev="h" type="message"/></message>', tables="")
    assert generate(tmp_path, raw, tmp_path / "out") == 2
    one_line(capsys.readouterr().err, "<field abbrev='h'>: an inline field of any message, and no message of scalar")


def test_4_a_message_abbreviation_with_a_digit_gives_case_files_the_schema_takes(tmp_path, capsys):
    """Found by generating random IMC.xml files: IMC allows digits in a message's abbreviation (as definitions.json
    does), but the case id pattern of vectors.schema.json did not, so such a folder could not be run."""
    raw = imc_xml('<message id="5" name="Sonar 3D" abbrev="Sonar3D"><field name="A" abbrev="a" type="uint8_t"/>'
                  '</message>', tables="")
    assert generate(tmp_path, raw, tmp_path / "out") == 0
    capsys.readouterr()
    assert main(["list", "--vectors", str(tmp_path / "out")]) == 0
    assert capsys.readouterr().out.startswith("imc/Sonar3D/")


# ---------------------------------------------------------------- the whole protocol's cache

def cli(cache: Path, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "imc_conformance.cli", *args], capture_output=True, text=True,
                          timeout=600, cwd=cache, env={**os.environ, "IMC_CONFORMANCE_CACHE": str(cache)})


@pytest.fixture(scope="module")
def whole_cache(tmp_path_factory):
    """A cache of its own with the imcpy sdist and IMC.xml (copied from this run's cache: no download) and the whole
    protocol's folder built once."""
    cache = tmp_path_factory.mktemp("cache")
    for name in ("IMC-imcpy-1.1.2.xml", "imcpy-1.1.2.tar.gz"):
        shutil.copy(cached(name), cache / name)
    done = cli(cache, "list", "--suite", "imc-full", "--message", "Heartbeat")
    assert done.returncode == 0, done.stderr
    return cache


def built(cache: Path) -> Path:
    (folder,) = [p for p in cache.glob("imc-whole-*") if p.is_dir() and "." not in p.name]
    return folder


def test_5_a_case_file_missing_from_the_cached_folder_is_never_a_message_left_out(whole_cache):
    """Item 5: a missing case file silently dropped its message (337 of 338 judged, exit 0)."""
    folder = built(whole_cache)
    (folder / "cases" / "350-EstimatedState.json").unlink()
    done = cli(whole_cache, "list", "--suite", "imc-full", "--message", "EstimatedState")
    assert done.returncode == 0 and len(done.stdout.splitlines()) == 544, done.stderr  # rebuilt
    assert built(whole_cache) == folder and (folder / "cases" / "350-EstimatedState.json").exists()


def test_5_a_file_its_manifest_lists_is_there_when_read(tmp_path):
    """Item 5, when the file goes after the folder was found whole: the reader refuses, naming it, in one line."""
    from imc_conformance.suites.corpus import read_cases
    from imc_conformance.suites.imc.suite import ImcSuite, load_whole

    suite = load_whole(built_copy(tmp_path))
    (suite.folder / "cases" / "150-Heartbeat.json").unlink()
    with pytest.raises(CorpusError, match=r"damaged, cases/150-Heartbeat.json is listed in its manifest but missing"):
        read_cases(suite, tuple(ImcSuite.case_folders.items()), groups=frozenset({"Heartbeat"}))


def built_copy(tmp_path: Path) -> Path:
    """A copy of the whole protocol's folder of this run's cache (the manifest sealed), to damage at will."""
    from imc_conformance.suites.imc.whole import whole_folder

    copy = tmp_path / "whole"
    shutil.copytree(whole_folder(), copy)
    return copy


def test_6_and_7_an_edited_case_file_is_refused_and_the_folder_rebuilt_also_without_its_manifest(whole_cache):
    """Item 6: an edited, schema-valid case file was used (EstimatedState judged on 1 case of 415, PASS; 544 since issue 31). Item 7:
    a folder without its manifest wedged imc-full for good ('Directory not empty' on every run)."""
    folder = built(whole_cache)
    path = folder / "cases" / "350-EstimatedState.json"
    doc = json.loads(path.read_text())
    doc["cases"] = doc["cases"][:1]
    path.write_text(json.dumps(doc))
    done = cli(whole_cache, "run", "--suite", "imc-full", "--adapter", "imcpy", "--message", "EstimatedState",
               "--no-progress")
    one_line(done.stderr, f"{folder}: damaged, cases/350-EstimatedState.json is not as built: nothing in it is used, "
                          "and it is built again at the next run")
    assert done.returncode == 2 and not (folder / "manifest.json").exists()  # item 7's state: no manifest
    done = cli(whole_cache, "list", "--suite", "imc-full", "--message", "EstimatedState")
    assert done.returncode == 0 and len(done.stdout.splitlines()) == 544, done.stderr
    assert built(whole_cache) == folder and json.loads((folder / "manifest.json").read_text())["sealed"] is True


def test_8_versions_sharing_a_cache_keep_each_others_folder_and_never_remove_one_in_use(tmp_path, monkeypatch):
    """Item 8: two versions sharing a cache deleted each other's folder mid-run (a traceback, no report) and rebuilt
    143 MB in turn. Each version has its folder; the ``KEEP`` used last are kept, and one a process holds never goes."""
    import fcntl

    from imc_conformance.suites.imc import whole

    for source in (cached("IMC-imcpy-1.1.2.xml"), cached("imcpy-1.1.2.tar.gz")):
        shutil.copy(source, tmp_path / source.name)
    monkeypatch.setenv("IMC_CONFORMANCE_CACHE", str(tmp_path))
    monkeypatch.setattr(whole, "write_folder", lambda folder, raw: {})  # a folder of nothing, as quick to build
    monkeypatch.setattr(whole, "_HELD", {})
    mine = whole.whole_folder()
    monkeypatch.setattr(whole, "__version__", "9.9.9")
    theirs = whole.whole_folder()
    assert theirs != mine and mine.exists() and theirs.exists()  # a second version keeps the first's folder
    older = []
    for n in range(3):  # three more, used before: with the two above, one too many
        folder = tmp_path / f"{whole.PREFIX}{n:016x}"
        folder.mkdir()
        (folder / "manifest.json").write_text('{"files": {}}')
        lock = folder.with_name(folder.name + ".lock")
        lock.touch()
        os.utime(lock, (time.time() - 1000 * (n + 1),) * 2)
        older.append(folder)
    held = open(older[2].with_name(older[2].name + ".lock"), "a+b")  # another process uses the oldest
    fcntl.flock(held, fcntl.LOCK_SH)
    whole.whole_folder()
    assert [p.exists() for p in (mine, theirs, *older)] == [True, True, True, False, True]
    held.close()
    whole.whole_folder()
    assert [p.exists() for p in (mine, theirs, *older)] == [True, True, True, False, False]


def cached(name: str) -> Path:
    """The imcpy sdist or its IMC.xml in this run's cache (fetched there if need be)."""
    from imc_conformance.suites.imc.imc_xml import fetch_imc_xml, imcpy_sdist

    return (imcpy_sdist() if name.endswith(".tar.gz") else fetch_imc_xml()).with_name(name)


def test_9_the_sdist_is_fetched_as_a_file_never_built_and_checked_against_its_pinned_hash(tmp_path, monkeypatch):
    """Item 9: the first use after a plain ``pip install`` failed: ``pip download`` of the sdist runs its build,
    which needs ``wheel`` (only in the test extra). The sdist is now downloaded from the index as a file (its
    page read, its link followed) and checked against the SHA-256 pinned in the code; nothing is built or run."""
    import urllib.request

    from imc_conformance.suites.imc import imc_xml

    sdist = cached("imcpy-1.1.2.tar.gz").read_bytes()
    served = {"https://pypi.org/simple/imcpy/": b'<a href="https://files.example/pk/imcpy-1.1.2.tar.gz#sha256=x">'
                                                 b'imcpy-1.1.2.tar.gz</a>',
              "https://files.example/pk/imcpy-1.1.2.tar.gz": sdist}

    class Response:
        def __init__(self, url, timeout):
            self.data = served[url]

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            return False

        def read(self, limit):
            return self.data[:limit]

    def no_build(*args, **kwargs):
        raise AssertionError(f"a program was run: {args}")

    monkeypatch.setattr(urllib.request, "urlopen", Response)
    monkeypatch.setattr(subprocess, "run", no_build)
    monkeypatch.setattr(subprocess, "Popen", no_build)
    monkeypatch.delenv("PIP_INDEX_URL", raising=False)
    monkeypatch.setenv("IMC_CONFORMANCE_CACHE", str(tmp_path))
    xml = imc_xml.fetch_imc_xml()
    assert xml.read_bytes() == cached("IMC-imcpy-1.1.2.xml").read_bytes()
    xml.write_bytes(xml.read_bytes().replace(b'abbrev="Heartbeat"', b'abbrev="Heartbeats"'))  # not as extracted
    assert imc_xml.fetch_imc_xml().read_bytes() == cached("IMC-imcpy-1.1.2.xml").read_bytes()
    (tmp_path / "imcpy-1.1.2.tar.gz").unlink()
    served["https://files.example/pk/imcpy-1.1.2.tar.gz"] = sdist[:-1] + b"\0"  # the index serves another file
    with pytest.raises(RuntimeError, match="not the imcpy-1.1.2.tar.gz of PyPI"):
        imc_xml.imcpy_sdist()
    assert not (tmp_path / "imcpy-1.1.2.tar.gz").exists()


# ---------------------------------------------------------------- fuzz

@pytest.fixture()
def reference_search():
    from imc_conformance.files import open_corpus
    from imc_conformance.fuzz.engine import Search
    from imc_conformance.sessions.library import LibrarySession
    from imc_conformance.suites.imc.mutants import MUTANTS

    suite, everything = open_corpus("imc", None, frozenset({"LblRange"}))
    bug = next(m for m in MUTANTS if m.name == "crc-unchecked")

    def search(**kw):
        sessions = {"no-crc-check": LibrarySession(bug(suite.defs), "no-crc-check")}
        return Search(suite, suite.fuzz_source("imc-5.4.30", everything), sessions, "imc-5.4.30", seed=0, budget=1,
                      **kw)
    return search


def test_11_the_sweep_builds_and_judges_bounded_batches_with_the_same_findings_whatever_their_size(
        reference_search, monkeypatch):
    """Item 11: ``--sweep N --duration S`` ignored the duration and built all N mutations in memory (740 MB and
    growing at 120 s for 100,000,000). The sweep now works in batches (the same findings whatever their size), checks
    the deadline between them, and N is bounded."""
    from imc_conformance.fuzz import engine

    whole = reference_search()
    whole.sweep(["LblRange"], 300)
    drawn = []
    real = engine.mutated_cases
    monkeypatch.setattr(engine, "mutated_cases", lambda *a: drawn.append(a[3]) or real(*a))
    monkeypatch.setattr(engine, "SWEEP_BATCH", 64)
    batched = reference_search()
    batched.sweep(["LblRange"], 300)
    assert drawn == [64, 64, 64, 64, 44]
    assert [f.case["id"] for f in batched.tally.findings] == [f.case["id"] for f in whole.tally.findings]
    assert batched.tally.judged == whole.tally.judged and whole.tally.findings


def test_11_the_sweep_stops_when_the_duration_is_spent(reference_search):
    late = reference_search(until=time.monotonic() - 1)  # a deadline already passed: not one batch
    late.sweep(["LblRange"], 300)
    assert late.tally.stopped == "the duration was spent" and late.tally.judged == {("LblRange", "sweep"): 0}


@pytest.mark.parametrize("option", ["--sweep", "--budget"])
def test_11_a_count_of_examples_beyond_the_bound_is_a_usage_error(capsys, option):
    refused(capsys, ["fuzz", "--adapter", "imcpy", "--in-process", option, "100000000", "--duration", "3"],
            f"argument {option}: '100000000': at most 1,000,000 per message")


def test_12_a_frame_finding_carrying_both_byte_orders_is_promoted_and_rebuilds_as_the_same_case(tmp_path):
    """Item 12: ``--promote`` crashed (ValueError) on a frame finding with a frame in each byte order."""
    import datetime as dt

    from imc_conformance.files import open_corpus
    from imc_conformance.fuzz import promote
    from imc_conformance.fuzz.engine import Finding

    suite, everything = open_corpus("imc", None, frozenset({"LblRange"}))
    source = suite.fuzz_source("imc-5.4.30", everything)
    frames = source.seed_frames("LblRange")
    for encoding in ("le", "be"):  # the mutated frame in either byte order
        frame = next(f for e, f in frames if e == encoding)
        case = source.frame_case("LblRange", encoding, frame, "none")
        assert set(case["frames"]) == {"le", "be"}  # a frame the reference decodes: judged in both orders
        record = promote.entry(Finding("LblRange", "frame", case, {}, "x deviates"), 0, ["x"], "imc-5.4.30", "0",
                               dt.date(2026, 1, 1))
        promote.merge(tmp_path / "promoted.json", "imc", [record])
        (rebuilt,) = promote.promoted_cases([record], {"imc-5.4.30": source})["LblRange"]
        assert rebuilt["id"] == case["id"] and rebuilt["frames"] == case["frames"]
    assert [r["id"] for r in promote.read(tmp_path / "promoted.json", "imc")] == [case["id"]]


# ---------------------------------------------------------------- shards and saved results

def shard(tmp_path: Path, k: int, n: int, *selection: str, name: str = "s") -> Path:
    path = tmp_path / f"{name}{k}.json"
    assert main(["run", "--adapter", "imcpy", "--no-progress", *selection, "--shard", f"{k}/{n}", "--json",
                 str(path)]) in (0, 1)
    return path


def test_14_a_merge_refuses_shards_of_different_selections_corpora_waivers_or_no_provenance(tmp_path, capsys):
    """Item 14: the shards of two selections (one shard run again with --message Heartbeat) merged as 'the 2 shards
    of the run', every case PASS, exit 0."""
    first = shard(tmp_path, 1, 2, "--message", "LblRange", "--message", "Heartbeat")
    second = shard(tmp_path, 2, 2, "--message", "Heartbeat", name="other")
    capsys.readouterr()
    assert main(["report", "--merge", str(first), str(second)]) == 2
    cases = json.loads(first.read_text())["provenance"]["selection"]["cases"]  # as many as the corpus holds today
    one_line(capsys.readouterr().err, "cannot merge: the shards differ in their selection: {'message': ['LblRange', "
                                      f"'Heartbeat'], 'id': [], 'tag': [], 'cases': {cases}}} and {{'message': ['Heartbeat']")
    right = shard(tmp_path, 2, 2, "--message", "LblRange", "--message", "Heartbeat")
    for key, value in (("corpus", "sha256:" + "0" * 64), ("errata", None), ("tool", "imc-conformance 0.0.1"),
                       ("waivers", {"file": "w.json", "sha256": "0" * 64, "waivers": 1})):
        doc = json.loads(right.read_text())
        doc["provenance"][key] = value
        changed = tmp_path / f"{key}.json"
        changed.write_text(json.dumps(doc))
        assert main(["report", "--merge", str(first), str(changed)]) == 2
        one_line(capsys.readouterr().err, f"the shards differ in their {key}")
    old = json.loads(right.read_text())
    old.pop("provenance")
    old.pop("causes", None)
    old.pop("headline")
    old["format"] = "imc-conformance-result/4"
    (tmp_path / "old.json").write_text(json.dumps(old))
    assert main(["report", "--merge", str(first), str(tmp_path / "old.json")]) == 2
    one_line(capsys.readouterr().err, "a shard records no provenance (a result of format 4 or before)")
    merged = tmp_path / "merged.json"
    assert main(["report", "--merge", str(first), str(right), "--json", str(merged)]) == 0
    made = json.loads(merged.read_text())["provenance"]
    assert made["selection"]["cases"] == cases and made["command"][:3] == ["imc-conformance", "report", "--merge"]


def test_15_an_empty_shard_is_a_result_of_no_case_and_merges(tmp_path, capsys):
    """Item 15: an empty shard exited 2 and wrote no result, so a passing sharded run could never be merged."""
    one = ["--id", "imc/LblRange/minimal"]
    paths = [tmp_path / f"s{k}.json" for k in (1, 2)]
    codes = [main(["run", "--adapter", "imcpy", "--no-progress", *one, "--shard", f"{k}/2", "--json", str(p)])
             for k, p in enumerate(paths, 1)]
    docs = [json.loads(p.read_text()) for p in paths]
    assert codes == [0, 0] and sorted(len(d["messages"]) for d in docs) == [0, 1]
    empty = next(d for d in docs if not d["messages"])
    assert empty["exit_code"] == 0 and any("0 of the selection's 1 cases" in n for n in empty["notes"])
    capsys.readouterr()
    merged = tmp_path / "merged.json"
    assert main(["report", "--merge", *map(str, paths), "--json", str(merged)]) == 0
    assert [c["id"] for m in json.loads(merged.read_text())["messages"] for c in m["cases"]] == one[1:]
    assert main(["run", "--adapter", "imcpy", "--no-progress", "--id", "imc/Nothing/*", "--shard", "1/2"]) == 2
    one_line(capsys.readouterr().err, "the selection matches no case")


@pytest.fixture()
def saved(tmp_path):
    path = tmp_path / "r.json"
    assert main(["run", "--adapter", "pyimclsts", "--no-progress", "--message", "LblRange", "--message", "TextMessage",
                 "--json", str(path)]) == 1  # both fail (pyimclsts checks no CRC: erratum P1)
    return path


def test_16_report_and_matrix_refuse_a_result_whose_message_verdict_contradicts_its_cases(saved, tmp_path, capsys):
    """Item 16: TextMessage edited from FAIL to PASS rendered PASS beside its failing cases, and matrix exited 0."""
    doc = json.loads(saved.read_text())
    text = next(m for m in doc["messages"] if m["name"] == "TextMessage")
    assert text["verdict"] == "FAIL"
    text["verdict"] = "PASS"
    edited = tmp_path / "edited.json"
    edited.write_text(json.dumps(doc))
    capsys.readouterr()
    for argv in (["report", str(edited)], ["matrix", str(edited)]):
        assert main(argv) == 2
        one_line(capsys.readouterr().err, "$.messages[0].verdict: PASS for TextMessage, whose cases give FAIL: a "
                                          "result that contradicts itself is not read")
    old = {k: v for k, v in doc.items() if k not in ("provenance", "shard", "causes", "headline")} | {"format": "imc-conformance-result/3"}
    (tmp_path / "old.json").write_text(json.dumps(old))  # written before today's message verdicts: derived again
    assert main(["report", str(tmp_path / "old.json"), "--json", str(tmp_path / "again.json")]) == 1
    again = json.loads((tmp_path / "again.json").read_text())
    assert next(m for m in again["messages"] if m["name"] == "TextMessage")["verdict"] == "FAIL"


@pytest.mark.parametrize("command", ["run", "fuzz"])
@pytest.mark.parametrize("option,value,says", [
    ("--timeout", "1e10", "give a positive, finite number of seconds, at most 86400"),
    ("--memory-limit", "99999999999999999999", "give a whole number of megabytes, at most 1048576 (0: no limit)"),
])
def test_17_a_timeout_or_memory_limit_too_large_for_the_system_is_a_usage_error(capsys, command, option, value, says):
    """Item 17: ``--timeout 1e10`` and ``--memory-limit 99999999999999999999`` ended in OverflowError tracebacks."""
    refused(capsys, [command, "--adapter", "imcpy-shim", "--message", "LblRange", option, value], says)


def test_17_the_largest_bounds_are_taken(tmp_path):
    assert main(["run", "--adapter", "imcpy-shim", "--message", "LblRange", "--no-progress", "--timeout", "86400",
                 "--memory-limit", "1048576"]) == 0


def test_18_case_files_built_for_other_definitions_are_refused_in_one_line(tmp_path, capsys):
    """Item 18: ``run --vectors DIR`` judged case files built for other definitions (a field widened from uint8 to
    uint16: 14 false FAILs), though every case records the hash of the definitions it was built from (LblRange's own
    cases, and those of HistoricData holding a LblRange inline)."""
    folder = tmp_path / "imc"
    shutil.copytree(VECTORS / "imc", folder)
    doc = json.loads((folder / "definitions.json").read_text())
    lbl = next(m for m in doc["messages"] if m["abbrev"] == "LblRange")
    field = next(f for f in lbl["fields"] if f["type"] == "uint8_t")
    field["type"] = "uint16_t"
    (folder / "definitions.json").write_text(json.dumps(doc))
    assert main(["run", "--adapter", "imcpy", "--no-progress", "--vectors", str(folder), "--message", "LblRange"]) == 2
    one_line(capsys.readouterr().err, ".definitions.LblRange: built for another definition of LblRange (sha256:")


def test_19_matrix_gives_every_column_its_own_label(tmp_path, capsys):
    """Item 19: ``matrix a=d1/r.json a=d2/r.json a=d3/r.json`` labelled two columns alike ('a (r.json)' twice)."""
    paths = []
    for n in (1, 2, 3):
        (tmp_path / f"d{n}").mkdir()
        paths.append(tmp_path / f"d{n}" / "r.json")
        assert main(["run", "--adapter", "imcpy", "--no-progress", "--message", "LblRange", "--json",
                     str(paths[-1])]) == 0
    capsys.readouterr()
    assert main(["matrix", *(f"a={p}" for p in paths), "--cases"]) == 0
    header = next(line for line in capsys.readouterr().out.splitlines() if line.startswith("| case"))
    labels = [cell.strip() for cell in header.strip("|").split("|")][1:]
    assert len(labels) == 3 and len(set(labels)) == 3 and labels[0] == "a"


# ---------------------------------------------------------------- provenance

def test_every_result_records_what_it_is_evidence_of_and_report_shows_it(saved, tmp_path, capsys):
    """Provenance (needed by item 14): the tool's version, the corpus's digest, the selection, the errata key, the
    waivers and the command line, in the result and in what report renders of it."""
    from imc_conformance import __version__

    waivers = tmp_path / "waivers.json"
    waivers.write_text(json.dumps({"waivers": [{"id": "imc/TextMessage/text/text/utf8", "reason": "known"}]}))
    path = tmp_path / "w.json"
    assert main(["run", "--adapter", "imcpy", "--no-progress", "--message", "TextMessage", "--errata", "imcpy",
                 "--waivers", str(waivers), "--json", str(path)]) == 1
    made = json.loads(path.read_text())["provenance"]
    manifest = (VECTORS / "imc" / "manifest.json").read_bytes()
    assert made == {"tool": f"imc-conformance {__version__}", "corpus": f"sha256:{hashlib.sha256(manifest).hexdigest()}",
                    "selection": {"message": ["TextMessage"], "id": [], "tag": [], "cases": made["selection"]["cases"]},
                    "errata": "imcpy", "waivers": {"file": str(waivers), "sha256": hashlib.sha256(
                        waivers.read_bytes()).hexdigest(), "waivers": 1},
                    "command": ["imc-conformance", "run", "--adapter", "imcpy", "--no-progress", "--message",
                                "TextMessage", "--errata", "imcpy", "--waivers", str(waivers), "--json", str(path)]}
    from imc_conformance.files import read_result
    from imc_conformance.render import RENDERERS
    from imc_conformance.render.common import provenance_lines

    assert RENDERERS["json"](read_result(path)) == path.read_text()  # read back exactly
    capsys.readouterr()
    md = tmp_path / "r.md"
    assert main(["report", str(path), "--markdown", str(md), "--html", str(tmp_path / "r.html")]) == 1
    out = capsys.readouterr().out
    for line in (f"corpus: {made['corpus']}", "selection: message TextMessage; cases", "errata key: imcpy",
                 "command: imc-conformance run --adapter imcpy"):
        assert line in out
    assert f"waivers: {waivers} (sha256:{made['waivers']['sha256']}, 1 in force)" in provenance_lines(read_result(path))
    assert "errata key&#58; imcpy" in md.read_text() and "corpus: sha256:" in (tmp_path / "r.html").read_text()


def test_the_corpus_digest_follows_what_the_run_judged_with(tmp_path, capsys):
    """The shipped corpus is named by its manifest's digest; a folder given instead, or one of its files changed,
    by the digest of what it holds."""
    folder = tmp_path / "imc"
    shutil.copytree(VECTORS / "imc", folder)
    digests = []
    for edit in (False, True):
        if edit:
            path = folder / "cases" / "200-LblRange.json"
            doc = json.loads(path.read_text())
            doc["cases"] = doc["cases"][:5]
            path.write_text(json.dumps(doc))
        out = tmp_path / f"r{edit}.json"
        assert main(["run", "--adapter", "imcpy", "--no-progress", "--vectors", str(folder), "--message", "LblRange",
                     "--json", str(out)]) == 0
        digests.append(json.loads(out.read_text())["provenance"]["corpus"])
    shipped = "sha256:" + hashlib.sha256((VECTORS / "imc" / "manifest.json").read_bytes()).hexdigest()
    assert len(set(digests + [shipped])) == 3
