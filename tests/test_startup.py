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
from imc_conformance.files import open_corpus, read_case_file
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
