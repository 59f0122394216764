"""The suite-generic core: nothing judged is dropped, errata come from the selected corpus under a declared key,
a saved result re-renders exactly, and the core names no suite."""

from __future__ import annotations

import ast
import json
import shutil
from pathlib import Path

import pytest

from imc_conformance.cli import main
from imc_conformance.core import runner
from imc_conformance.core.runner import run_cases
from imc_conformance.files import read_result
from imc_conformance.render import RENDERERS
from imc_conformance.sessions.library import LibrarySession
from imc_conformance.suites import load_suite, names, variants
from imc_conformance.suites.imc.paths import imc_data

CORE = Path(__file__).resolve().parents[1] / "conformance" / "core"
P1_CASE = "imc/LblRange/crc/header-timestamp/le"  # fails with pyimclsts: erratum P1 (it checks no CRC)

ACCEPTS_EVERYTHING = """
from imc_conformance.suites.imc import codec
from imc_conformance.suites.imc.definitions import load_definitions
D = load_definitions()
class Accepts:
    def hello(self): return {"implementation": "imcpy-lookalike that accepts everything", "suites": ["imc"],
                             "byte_orders": ["le", "be"]}
    def encode(self, s, m, o): return codec.encode(D, m, o)
    def decode(self, s, f):
        try: return codec.decode(D, f)
        except codec.FrameError: return {"abbrev": "LblRange", "header": {}, "fields": {}}
adapter = Accepts()
"""


def test_a_case_filed_under_another_message_is_an_error_not_dropped(tmp_path, capsys):
    doc = json.loads(imc_data("cases", "200-LblRange.json").read_text(encoding="utf-8"))
    for case in doc["cases"]:
        if case["expect"] == "invalid":  # as in the report: 64 of 93 cases renamed, the rest reached the result
            case["id"] = case["id"].replace("imc/LblRange/", "imc/LblRangeX/")
    (tmp_path / "200-LblRange.json").write_text(json.dumps(doc))
    (tmp_path / "mutant.py").write_text(ACCEPTS_EVERYTHING)
    code = main(["run", "--adapter", f"{tmp_path / 'mutant.py'}:adapter", "--no-progress", "--vectors", str(tmp_path)])
    assert code == 2
    assert "200-LblRange.json: $.cases[31].id: 'imc/LblRangeX/sync/first-byte/le' is not under imc/LblRange/" \
        in capsys.readouterr().err


def test_a_file_filed_under_an_unknown_message_is_an_error(tmp_path, capsys):
    doc = json.loads(imc_data("cases", "200-LblRange.json").read_text(encoding="utf-8"))
    doc["message"]["abbrev"] = "LblRangeX"
    (tmp_path / "200-LblRange.json").write_text(json.dumps(doc))
    assert main(["list", "--vectors", str(tmp_path)]) == 2
    assert "the file is filed under 'LblRangeX', which is not a message of the suite 'imc'" in capsys.readouterr().err


def test_the_runner_never_judges_a_case_it_cannot_file(suite, cases, imcpy_adapter):
    stray = cases[0].__class__(cases[0].id, "NoSuchMessage", cases[0].kind, cases[0].data)
    with pytest.raises(ValueError, match="NoSuchMessage"):
        run_cases(LibrarySession(imcpy_adapter, "imcpy"), suite, [stray], edition="imc-5.4.30", adapter="imcpy")


def errata_of(path: Path) -> list[str]:
    doc = json.loads(path.read_text(encoding="utf-8"))
    return [e for m in doc["messages"] for c in m["cases"] if c["id"] == P1_CASE for e in c.get("errata", [])]


def test_errata_are_read_from_the_selected_corpus(tmp_path, capsys):
    corpus = tmp_path / "imc"
    shutil.copytree(imc_data(), corpus)
    errata = json.loads((corpus / "errata.json").read_text(encoding="utf-8"))
    errata["errata"] = [e for e in errata["errata"] if e["id"] != "P1"]
    (corpus / "errata.json").write_text(json.dumps(errata))
    packaged, selected = tmp_path / "packaged.json", tmp_path / "selected.json"
    pyimclsts = ["run", "--adapter", "pyimclsts", "--no-progress", "--id", P1_CASE]
    assert main([*pyimclsts, "--json", str(packaged)]) == 1
    assert main([*pyimclsts, "--vectors", str(corpus), "--json", str(selected)]) == 1
    assert errata_of(packaged) == ["P1"] and errata_of(selected) == []


def test_errata_apply_by_the_key_the_adapter_declares_not_by_its_name(tmp_path, capsys):
    (tmp_path / "lookalike.py").write_text(
        "from imc_conformance.adapters.pyimclsts_adapter import adapter as real\n"
        "class Lookalike:\n"
        "    def __init__(self): self.real = real()\n"
        "    def hello(self): return {**self.real.hello(), 'errata': None}  # named 'pyimclsts ...', declares no key\n"
        "    def encode(self, *a): return self.real.encode(*a)\n"
        "    def decode(self, *a): return self.real.decode(*a)\n")
    spec = f"{tmp_path / 'lookalike.py'}:Lookalike"
    undeclared, chosen = tmp_path / "undeclared.json", tmp_path / "chosen.json"
    assert main(["run", "--adapter", spec, "--no-progress", "--id", P1_CASE, "--json", str(undeclared)]) == 1
    assert main(["run", "--adapter", spec, "--no-progress", "--id", P1_CASE, "--errata", "pyimclsts", "--json", str(chosen)]) == 1
    assert errata_of(undeclared) == [] and errata_of(chosen) == ["P1"]


def test_a_saved_result_re_renders_byte_for_byte(suite, cases, imcpy_adapter, monkeypatch, tmp_path):
    clock = iter([0.0, 0.1349])  # 0.1349 s shows as 0.13; rounded to milliseconds, 0.135 would show as 0.14
    monkeypatch.setattr(runner.time, "perf_counter", lambda: next(clock))
    result = run_cases(LibrarySession(imcpy_adapter, "imcpy"), suite, [c for c in cases if c.group == "TextMessage"],
                       edition="imc-5.4.30", adapter="imcpy")
    path = tmp_path / "r.json"
    path.write_text(RENDERERS["json"](result), encoding="utf-8")
    again = read_result(path)
    for fmt, render in RENDERERS.items():
        assert render(again) == render(result), fmt


def test_the_core_and_the_case_kinds_name_no_suite():
    """No module of the core, of a case kind or of captures mentions a suite's name; the core imports nothing
    outside itself."""
    for path in [*CORE.parent.glob("kinds/*/*.py"), *CORE.parent.glob("capture/*.py")]:
        text = path.read_text(encoding="utf-8")
        assert not any(f'"{n}"' in text or f"'{n}'" in text for n in names()), path.name
    for path in CORE.glob("*.py"):
        text = path.read_text(encoding="utf-8")
        for name in names():
            assert f'"{name}"' not in text and f"'{name}'" not in text, (path.name, name)
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, ast.ImportFrom) and node.level:
                assert node.level == 1, (path.name, node.module)  # relative imports stay inside core/


def test_every_suite_loads_and_declares_what_the_core_needs():
    for name in names():
        suite = load_suite(name)
        assert suite.name == variants().get(name, (name,))[0] and suite.editions and suite.encodings and suite.groups
        assert set(suite.case_folders.values()) <= set(suite.kinds) and suite.adapters
