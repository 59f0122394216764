"""Start-up without a change of verdict: the packaged corpus is trusted by the content hashes its generator
recorded (a changed file is checked again), a selection reads only its files, and the command line imports
nothing heavy until a command runs."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys

import pytest

from imc_conformance.errors import CorpusError
from imc_conformance.files import open_corpus
from imc_conformance.suites.corpus import read_case_file
from imc_conformance.suites import load_suite
from imc_conformance.suites.data_suite import MANIFEST, manifest_text


@pytest.mark.parametrize("name", ["imc", "ros_acomms"])
def test_the_manifest_is_what_the_generator_writes(name):
    suite = load_suite(name)
    build = __import__(f"imc_conformance.suites.{name}.corpus.build", fromlist=["build_corpus"])
    defs = suite.defs
    files = build.build_corpus(defs)
    assert (suite.packaged / MANIFEST).read_text(encoding="utf-8") == manifest_text(suite, files), \
        "run `imc-conformance generate` and commit the result"


def test_a_packaged_file_changed_since_it_was_built_is_checked_again(tmp_path, monkeypatch):
    suite = load_suite("imc")
    copy = tmp_path / "imc"
    shutil.copytree(suite.packaged, copy)
    monkeypatch.setattr(suite, "packaged", copy)
    monkeypatch.setattr(suite, "folder", copy)
    path = copy / "cases" / "200-LblRange.json"
    assert read_case_file(suite, "vector", path)  # as built: trusted
    doc = json.loads(path.read_text(encoding="utf-8"))
    doc["cases"][0]["message"]["fields"]["range"] = "abc"
    path.write_text(json.dumps(doc), encoding="utf-8")
    with pytest.raises(CorpusError, match=r"\$\.cases\[0\]\.message\.fields\.range: 'abc' is not a fp32_t value"):
        read_case_file(suite, "vector", path)


def test_a_selection_reads_only_its_messages_files():
    _, some = open_corpus("imc", None, frozenset({"LblRange"}))
    _, every = open_corpus("imc")
    assert {c.group for c in some if c.kind == "vector"} == {"LblRange"}
    assert [c for c in every if c.group == "LblRange"] == [c for c in some if c.group == "LblRange"]


def test_the_command_line_imports_nothing_heavy_to_start():
    code = ("import sys, imc_conformance.cli as cli; cli.build_parser(); "
            "print(sorted(m for m in ('jsonschema', 'jinja2', 'rich', 'scapy', 'imcpy', 'hypothesis', "
            "'imc_conformance.kinds.scenario', 'imc_conformance.files', 'imc_conformance.render.html') if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"



def loaded_after(code: str) -> set[str]:
    """The modules a fresh interpreter holds after running ``code`` (which imports the CLI as ``cli``)."""
    done = subprocess.run([sys.executable, "-c", f"import sys, io, contextlib, imc_conformance.cli as cli\n{code}\n"
                           "print(' '.join(sys.modules))"], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    return set(done.stdout.split())


def test_version_imports_no_command():
    loaded = loaded_after("with contextlib.suppress(SystemExit): cli.main(['--version'])")
    assert {m for m in loaded if m.startswith(("imc_conformance.commands", "imc_conformance.suites"))} == set()


def test_a_run_of_byte_vectors_imports_no_live_kind_and_no_build_tools():
    """A run of one message with a library adapter: the case kinds it does not plan, the native build tools, and
    importlib.metadata (the adapter's version is read from its installed folder's name) stay unloaded."""
    loaded = loaded_after("with contextlib.redirect_stdout(io.StringIO()): "
                          "cli.main(['run', '--adapter', 'imcpy', '--message', 'LblRange', '--no-progress'])")
    assert "imc_conformance.kinds.vector" in loaded
    assert {"imc_conformance.kinds.scenario.machine", "imc_conformance.kinds.robustness", "imc_conformance.native",
            "importlib.metadata", "tarfile"} & loaded == set()


# ---------------------------------------------------------------- shards

def test_shards_partition_the_selection_by_case_id():
    from imc_conformance.core.cases import select_cases, shard_of

    _, cases = open_corpus("imc")
    shards = [select_cases(cases, "imc-5.4.30", shard=(k, 4)) for k in range(1, 5)]
    ids = [c.id for shard in shards for c in shard]
    assert sorted(ids) == sorted(c.id for c in select_cases(cases, "imc-5.4.30")) and len(ids) == len(set(ids))
    assert all(shard_of(c.id, 4) == k for k, shard in enumerate(shards, 1) for c in shard)


def test_merged_shards_are_the_whole_run(tmp_path, capsys):
    from imc_conformance.cli import main

    whole = tmp_path / "whole.json"
    code = main(["run", "--adapter", "imcpy", "--no-progress", "--message", "LblRange", "--message", "AcousticStatus",
                 "--json", str(whole)])
    parts = [tmp_path / f"shard{k}.json" for k in (1, 2, 3)]
    for k, part in enumerate(parts, 1):
        main(["run", "--adapter", "imcpy", "--no-progress", "--message", "LblRange", "--message", "AcousticStatus",
              "--shard", f"{k}/3", "--json", str(part)])
    merged = tmp_path / "merged.json"
    assert main(["report", "--merge", *map(str, reversed(parts)), "--json", str(merged)]) == code

    def cases(path):
        doc = json.loads(path.read_text())
        return [(m["name"], c["id"], c["verdict"], c["checks"]) for m in doc["messages"] for c in m["cases"]]
    assert cases(merged) == cases(whole)
    capsys.readouterr()
    assert main(["report", "--merge", str(parts[0]), str(parts[1])]) == 2
    assert "shard 3/3 missing" in capsys.readouterr().err
    assert main(["report", "--merge", str(parts[0]), str(parts[0]), str(parts[2])]) == 2
    assert "not each of one run of 3" in capsys.readouterr().err
    assert main(["report", "--merge", str(whole), str(parts[0])]) == 2
    assert "is not a shard" in capsys.readouterr().err


def test_a_shard_count_beyond_the_bound_is_one_line_not_a_hang(tmp_path, capsys):
    """A saved result claiming 10**12 shards (by hand, or a hostile file): refused when read, never a merge that
    lists every shard it would need."""
    from imc_conformance.cli import main
    from imc_conformance.core.shards import merge
    from imc_conformance.files import read_result
    from imc_conformance.limits import SHARDS_MAX

    from imc_conformance.paths import VECTORS

    schema = json.loads((VECTORS / "schema" / "result.schema.json").read_text(encoding="utf-8"))
    assert schema["properties"]["shard"]["properties"]["of"]["maximum"] == SHARDS_MAX
    parts = []
    for k in (1, 2):
        path = tmp_path / f"s{k}.json"
        main(["run", "--adapter", "imcpy", "--no-progress", "--message", "LblRange", "--shard", f"{k}/2", "--json",
              str(path)])
        doc = json.loads(path.read_text())
        doc["shard"]["of"] = 10**12
        path.write_text(json.dumps(doc))
        parts.append(path)
    capsys.readouterr()
    assert main(["report", "--merge", *map(str, parts)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "maximum" in err
    results = []
    for path in parts:
        doc = json.loads(path.read_text())
        doc["shard"]["of"] = 2
        path.write_text(json.dumps(doc))
        results.append(read_result(path))
    for r in results:
        r.shard = (r.shard[0], 10**12)
    with pytest.raises(ValueError, match="split into 2 to"):
        merge(results, [], {})


def test_the_pytest_plugin_gives_the_same_outcomes_under_xdist(tmp_path):
    pytest.importorskip("xdist")
    outcomes = {}
    for workers in ([], ["-n", "2"]):
        done = subprocess.run([sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-q", "-rA", *workers,
                               "--conformance-adapter=pyimclsts", "--conformance-id", "imc/LblRange/*"],
                              capture_output=True, text=True, timeout=300, cwd=tmp_path)
        outcomes[bool(workers)] = sorted(line.split(" - ")[0] for line in done.stdout.splitlines()
                                         if line.startswith(("PASSED ", "FAILED ", "SKIPPED ")))
    assert outcomes[True] == outcomes[False] and any(o.startswith("FAILED") for o in outcomes[False])


@pytest.mark.parametrize("adapter, code", [("pyimclsts", 0), ("imcpy", 1)])
def test_a_cause_waiver_is_stale_in_merged_shards_only_when_it_waived_nothing(adapter, code, tmp_path, capsys):
    """pyimclsts accepts frames with a wrong CRC (the waiver waives them in each shard); imcpy refuses them (the waiver
    is stale in every shard, and so in the merge)."""
    from imc_conformance.cli import main

    waivers = tmp_path / "w.json"
    waivers.write_text(json.dumps({"waivers": [{"cause": "accepts/rule:crc", "reason": "no CRC check yet"}]}))
    parts = [tmp_path / f"shard{k}.json" for k in (1, 2)]
    for k, part in enumerate(parts, 1):
        main(["run", "--adapter", adapter, "--no-progress", "--id", "imc/LblRange/crc/*", "--waivers", str(waivers),
              "--shard", f"{k}/2", "--json", str(part)])
    merged = tmp_path / "merged.json"
    assert main(["report", "--merge", *map(str, parts), "--json", str(merged)]) == code
    doc = json.loads(merged.read_text())
    stale = [n for n in doc["notes"] if n.startswith("WAIVER_STALE")]
    assert doc.get("stale_waivers", []) == ([] if code == 0 else ["cause accepts/rule:crc"])
    assert len(stale) == (code == 1), doc["notes"]
