"""The implementation matrix: saved results side by side, never mixing suites or editions, a narrower selection
labelled, what implementations say escaped."""

from __future__ import annotations

import json

from imc_conformance.cli import main


def saved(tmp_path, name, *args):
    path = tmp_path / f"{name}.json"
    assert main(["run", "--no-progress", "--json", str(path), *args]) in (0, 1)
    return path


def test_matrix_of_two_suites_and_a_narrower_run(tmp_path, capsys):
    imcpy = saved(tmp_path, "imcpy", "--adapter", "imcpy", "--message", "LblRange", "--message", "RSSI")
    narrow = saved(tmp_path, "pyimclsts", "--adapter", "pyimclsts", "--message", "LblRange", "--tag", "valid")
    ros = saved(tmp_path, "rosbags", "--suite", "ros_acomms", "--adapter", "rosbags", "--message", "CST")
    md, html = tmp_path / "m.md", tmp_path / "m.html"
    assert main(["matrix", str(imcpy), f"narrow={narrow}", str(ros), "--markdown", str(md), "--html", str(html)]) == 0
    text = md.read_text()
    assert text.count("## ") == 2  # one table per suite and edition
    row = next(line for line in text.splitlines() if line.startswith("| LblRange"))
    cells = row.split(" | ")
    assert "**PASS**" in cells[1] and "≠" in cells[2]  # pyimclsts judged only the valid cases: labelled
    assert "| RSSI | **PASS**" in text and "| RSSI |" in text and " — |" in text.split("| RSSI |")[1].splitlines()[0]
    assert "errata R1" in text  # rosbags' CST failure is a documented erratum
    assert "<table>" in html.read_text()


def test_matrix_escapes_what_implementations_say(tmp_path, capsys):
    path = saved(tmp_path, "imcpy", "--adapter", "imcpy", "--message", "LblRange")
    doc = json.loads(path.read_text())
    doc["implementation"] = "<script>alert(1)</script>\u202e|evil"
    path.write_text(json.dumps(doc))
    md, html = tmp_path / "m.md", tmp_path / "m.html"
    assert main(["matrix", str(path), "--markdown", str(md), "--html", str(html)]) == 0
    assert "<script>" not in html.read_text() and "&lt;script&gt;" in html.read_text()
    assert "<script>" not in md.read_text() and "\u202e" not in md.read_text() and "\\u202e" in md.read_text()


def test_matrix_refuses_what_is_not_a_result(tmp_path, capsys):
    bad = tmp_path / "bad.json"
    bad.write_text("{}")
    assert main(["matrix", str(bad)]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1
