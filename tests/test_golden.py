"""The IMC suite's case ids, expectations and verdicts are pinned: the suite-generic core changed none of them.

The golden files were written by the runner before the core became generic (list output for both editions, to
which the scenarios were appended when that case kind came) and by this one (a whole JSON result, whose format
became 3 with the scenarios, 5 with its provenance, 6 with its headline); a change to any of them must be deliberate: regenerate and review.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import pytest

from imc_conformance.cli import main

GOLDEN = Path(__file__).resolve().parent / "golden"


@pytest.mark.parametrize("edition", ["imc-5.4.30", "imc-5.4.11"])
def test_list_output_is_pinned(edition, capsys):
    assert main(["list", "--edition", edition]) == 0
    assert capsys.readouterr().out == (GOLDEN / f"list-{edition}.tsv").read_text(encoding="utf-8")


def test_a_json_result_is_pinned(tmp_path, capsys):
    """Pinned but for when it ran, where it wrote, and the digest of the corpus (which any change of the shipped
    corpus changes: it is checked to be the manifest's)."""
    from imc_conformance.paths import VECTORS

    path = tmp_path / "r.json"
    assert main(["run", "--adapter", "imcpy", "--no-progress", "--message", "TextMessage", "--json", str(path)]) == 0
    doc = json.loads(path.read_text(encoding="utf-8"))
    doc.update(started="2026-01-01T00:00:00+00:00", duration=0.0)
    made = doc["provenance"]
    assert made["corpus"] == "sha256:" + hashlib.sha256((VECTORS / "imc" / "manifest.json").read_bytes()).hexdigest()
    assert made["command"][-1] == str(path)
    made.update(corpus="sha256:" + "0" * 64, command=made["command"][:-1] + ["r.json"])
    assert doc == json.loads((GOLDEN / "run-imcpy-TextMessage.json").read_text(encoding="utf-8"))


@pytest.mark.parametrize("args, code", [
    (["--message", "LblRange"], 0),
    (["--id", "imc/TextMessage/text/text/utf8"], 0),  # imcpy's lossy text: implementation-defined (erratum I3)
    (["--adapter", "pyimclsts", "--id", "imc/LblRange/crc/*"], 1),
    (["--adapter", "pyimclsts", "--message", "LblRange"], 1),
    (["--adapter", "no_such_module:adapter"], 2),
    (["--message", "NoSuchMessage"], 2),
])
def test_exit_codes_are_pinned(args, code, capsys):
    assert main(["run", "--no-progress", *args]) == code
