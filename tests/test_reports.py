"""The report renderers on real runs: imcpy (passing), pyimclsts (failures its errata explain: no CRC check, P1) and a
deliberately broken encoder
(LblRange.range off by one, so encode checks fail with byte differences), plus a hostile result whose
implementation-provided text tries to inject markup into every format.
"""

from __future__ import annotations

import copy
import json
import re
import subprocess
import xml.etree.ElementTree as ET
from html.parser import HTMLParser
from pathlib import Path

import pytest
from jsonschema import Draft202012Validator

from imc_conformance.suites.imc import codec
from imc_conformance.adapter_api import Rejected
from imc_conformance.core.results import ByteDiff
from imc_conformance.core.verdicts import Verdict
from imc_conformance.sessions.library import LibrarySession
from imc_conformance.paths import VECTORS
from imc_conformance.render import RENDERERS, html as html_module
from imc_conformance.render.html import render_html
from imc_conformance.render.json_result import render_json
from imc_conformance.render.junit import render_junit
from imc_conformance.render.markdown import render_markdown
from imc_conformance.core.results import RunResult
from imc_conformance.core.runner import run_cases

SCHEMA = json.loads((VECTORS / "schema" / "result.schema.json").read_text(encoding="utf-8"))
CHROMIUM = Path("/usr/bin/chromium")
EVIL = "<script>alert(1)</script> <img src=x onerror=alert(2)> ]]> \x00 \x1b[31mred\x1b[0m a|b `tick` & done"
FAILING_CASE = "imc/LblRange/minimal"


class BrokenEncoder:
    """The reference codec, except that it encodes LblRange.range one metre too long."""

    def __init__(self, defs):
        self.defs = defs

    def hello(self) -> dict:
        return {"implementation": "broken-encoder 0.1 (LblRange.range + 1)", "suites": ["imc"], "byte_orders": ["le", "be"]}

    def encode(self, suite, message, byte_order):
        message = copy.deepcopy(message)
        fields = message.get("fields", {})
        if message.get("abbrev") == "LblRange" and isinstance(fields.get("range"), (int, float)):
            fields["range"] += 1.0
        try:
            return codec.encode(self.defs, message, byte_order)
        except codec.EncodeError as exc:
            raise Rejected(str(exc), exc.rule) from exc

    def decode(self, suite, frame):
        try:
            return codec.decode(self.defs, frame)
        except codec.FrameError as exc:
            raise Rejected(str(exc), exc.rule) from exc


@pytest.fixture(scope="module")
def imcpy_result(suite, cases, imcpy_adapter):
    return run_cases(LibrarySession(imcpy_adapter, "imcpy"), suite, cases, edition="imc-5.4.30", adapter="imcpy")


@pytest.fixture(scope="module")
def pyimclsts_result(suite, cases, pyimclsts_adapter):
    """A real implementation's failures: pyimclsts over three messages (its errata explain every one)."""
    chosen = [c for c in cases if c.group in ("Announce", "LblRange", "TextMessage")]
    return run_cases(LibrarySession(pyimclsts_adapter, "pyimclsts"), suite, chosen, edition="imc-5.4.30",
                     adapter="pyimclsts")


@pytest.fixture(scope="module")
def broken_result(suite, defs, cases):
    return run_cases(LibrarySession(BrokenEncoder(defs), "broken"), suite, cases, edition="imc-5.4.30", adapter="broken")


@pytest.fixture(scope="module")
def hostile_result(broken_result):
    """The broken run with hostile text wherever the implementation speaks: its name, stderr, a check's detail."""
    doc = broken_result.to_dict()
    doc["implementation"] = doc["stderr"] = EVIL
    doc["notes"] = [EVIL]
    case = next(c for m in doc["messages"] for c in m["cases"] if c["id"] == FAILING_CASE)
    next(k for k in case["checks"] if k["verdict"] == "FAIL")["detail"] = EVIL
    return RunResult.from_dict(doc)


def test_registry():
    assert RENDERERS == {"json": render_json, "junit": render_junit, "markdown": render_markdown, "html": render_html}


def test_runs_fail_as_intended(imcpy_result, pyimclsts_result, broken_result):
    assert "FAIL" not in imcpy_result.summary and imcpy_result.exit_code() == 0
    assert pyimclsts_result.summary["FAIL"] > 100 and pyimclsts_result.exit_code() == 1
    failing = {c.id for c in broken_result.cases if c.verdict is Verdict.FAIL}
    assert FAILING_CASE in failing and all(i.startswith("imc/LblRange/") for i in failing)


# --- JSON ---------------------------------------------------------------------------------------------------------

def test_result_schema_is_documented_and_strict():
    Draft202012Validator.check_schema(SCHEMA)
    assert SCHEMA["$id"] == "urn:imc-conformance:schema:result" and SCHEMA["title"] and SCHEMA["description"]
    assert SCHEMA["additionalProperties"] is False
    assert SCHEMA["$defs"]["verdict"]["enum"] == [v.value for v in Verdict]

    def undocumented(node, where):
        if isinstance(node, dict):
            for name, sub in node.get("properties", {}).items():
                if "description" not in sub:
                    yield f"{where}/{name}"
            for key, sub in node.items():
                yield from undocumented(sub, f"{where}/{key}")
        elif isinstance(node, list):
            for i, sub in enumerate(node):
                yield from undocumented(sub, f"{where}/{i}")

    assert not list(undocumented(SCHEMA, "#"))
    for name in ("message", "case", "check", "diff"):
        assert SCHEMA["$defs"][name]["additionalProperties"] is False


@pytest.mark.parametrize("which", ["imcpy_result", "hostile_result"])  # hostile: the broken run, hostile text
def test_json_validates_and_round_trips(which, request):
    result = request.getfixturevalue(which)
    text = render_json(result)
    doc = json.loads(text)
    validator = Draft202012Validator(SCHEMA, format_checker=Draft202012Validator.FORMAT_CHECKER)
    errors = [f"{list(e.absolute_path)}: {e.message}" for e in validator.iter_errors(doc)]
    assert not errors, errors[:5]
    assert render_json(RunResult.from_dict(doc)) == text


def _older(doc: dict, version: int) -> dict:
    """``doc`` as formats 1 to 5 wrote it: before its headline and required messages; formats 1 to 4: before provenance
    and causes; formats 1 to 3: before shards; formats 1 and 2: IMC only, numeric message ids, no title (format 1: no
    completeness, incidents or check kinds)."""
    doc = {k: v for k, v in doc.items() if k not in ("headline", "required")}
    if version == 5:
        return doc | {"format": "imc-conformance-result/5"}
    doc = {k: v for k, v in doc.items() if k not in ("provenance", "causes")}
    if version == 4:
        return doc | {"format": "imc-conformance-result/4"}
    if version == 3:
        return {k: v for k, v in doc.items() if k != "shard"} | {"format": "imc-conformance-result/3"}
    old = {k: v for k, v in doc.items() if k != "title"}
    old["format"] = f"imc-conformance-result/{version}"
    old["messages"] = [{**{k: v for k, v in m.items() if k != "key"}, "id": int(m["key"])} for m in doc["messages"]]
    if version == 1:
        for key in ("complete", "incidents", "untested"):
            old.pop(key)
    return old


@pytest.mark.parametrize("version", [1, 2, 3, 4, 5])
def test_report_reads_the_older_formats(version, pyimclsts_result, tmp_path):
    """An older result has no causes: they are grouped on reading from what it keeps (the rule, the id), the same
    cases in the same groups where the run's groups rest on the rule."""
    from imc_conformance.files import read_result

    path = tmp_path / f"r{version}.json"
    path.write_text(json.dumps(_older(pyimclsts_result.to_dict(), version)), encoding="utf-8")
    again = json.loads(render_json(read_result(path)))
    now = json.loads(render_json(pyimclsts_result))
    assert {k: v for k, v in again.items() if k != "causes"} == {k: v for k, v in now.items() if k != "causes"}
    assert sorted(i for c in again["causes"] for i in c["cases"]) == sorted(i for c in now["causes"] for i in c["cases"])
    assert [c for c in again["causes"] if c["key"].startswith("accepts/")] == \
        [c for c in now["causes"] if c["key"].startswith("accepts/")]


def test_schema_rejects_broken_documents(broken_result):
    validator = Draft202012Validator(SCHEMA)
    good = json.loads(render_json(broken_result))
    good["messages"] = good["messages"][:1]
    for mutate in (lambda d: d.update(extra=1), lambda d: d.update(format="imc-conformance-result/1"),
                   lambda d: d["messages"][0]["cases"][0].update(verdict="MAYBE"),
                   lambda d: d["messages"][0]["cases"][0].update(surprise=True),
                   lambda d: d["messages"][0]["cases"][0]["checks"][0].update(expected="xyz"),
                   lambda d: d.pop("summary")):
        doc = copy.deepcopy(good)
        mutate(doc)
        assert not validator.is_valid(doc)


# --- JUnit --------------------------------------------------------------------------------------------------------

def junit_tree(result) -> ET.Element:
    return ET.fromstring(render_junit(result).encode("utf-8"))


def test_junit_structure_and_counts(pyimclsts_result):
    root = junit_tree(pyimclsts_result)
    suites = root.findall("testsuite")
    assert [s.get("name") for s in suites] == [f"imc/{m.name}" for m in pyimclsts_result.messages]
    assert len(root.findall("testsuite/testcase")) == len(pyimclsts_result.cases) == int(root.get("tests"))
    summary = pyimclsts_result.summary
    failures = summary.get("FAIL", 0) + summary.get("WAIVER_STALE", 0)
    errors = sum(summary.get(v, 0) for v in ("CRASH", "TIMEOUT", "ADAPTER_ERROR"))
    assert int(root.get("failures")) == len(root.findall(".//failure")) == failures > 100
    assert int(root.get("errors")) == len(root.findall(".//error")) == errors
    assert int(root.get("skipped")) == len(root.findall(".//skipped")) == summary.get("UNSUPPORTED", 0)
    for suite, message in zip(suites, pyimclsts_result.messages):
        assert int(suite.get("tests")) == len(suite.findall("testcase")) == len(message.cases)
        assert int(suite.get("failures")) == len(suite.findall("testcase/failure"))
    case = root.find(".//testcase[@name='imc/Announce/crc/header-timestamp/le']")
    assert case.get("classname") == "imc.Announce"
    assert case.find("failure").get("type") == "FAIL" and "errata: P1" in case.find("failure").text
    impl_defined = next(c for c in pyimclsts_result.cases if c.verdict is Verdict.IMPL_DEFINED)
    assert "IMPL_DEFINED" in root.find(f".//testcase[@name='{impl_defined.id}']/system-out").text


def test_junit_strict_non_strict_and_waivers(broken_result):
    doc = broken_result.to_dict()
    cases = [c for m in doc["messages"] for c in m["cases"] if c["verdict"] == "FAIL"]
    cases[0]["verdict"], cases[1]["verdict"], cases[1]["waiver"] = "NON_STRICT", "WAIVED", "known"
    lenient = RunResult.from_dict(doc)
    root = junit_tree(lenient)
    assert "NON_STRICT" in root.find(f".//testcase[@name='{cases[0]['id']}']/system-out").text
    assert "waived (known)" in root.find(f".//testcase[@name='{cases[1]['id']}']/system-out").text
    strict = RunResult.from_dict(dict(doc, strict=True))
    failure = junit_tree(strict).find(f".//testcase[@name='{cases[0]['id']}']/failure")
    assert failure.get("type") == "NON_STRICT"


def test_junit_escapes_implementation_text(hostile_result):
    text = render_junit(hostile_result)
    assert "<script>" not in text and "<img" not in text and "\x00" not in text and "\x1b" not in text
    root = ET.fromstring(text.encode("utf-8"))
    assert not root.findall(".//script") and not root.findall(".//img")
    kept = "<script>alert(1)</script> <img src=x onerror=alert(2)> ]]>"
    assert kept in root.get("name")
    assert root.find("testsuite/system-err").text.startswith(kept)
    failure = root.find(f".//testcase[@name='{FAILING_CASE}']/failure")
    assert kept in failure.get("message") and "\\x00 \\x1b[31mred\\x1b[0m a|b `tick` & done" in failure.text
    assert root.find("testsuite/properties/property[@name='implementation']").get("value").startswith(kept)


# --- Markdown -----------------------------------------------------------------------------------------------------

def tables(text: str) -> list[list[str]]:
    """The Markdown tables of ``text``: runs of lines starting with a pipe."""
    out, current = [], []
    for line in text.splitlines() + [""]:
        if line.startswith("|"):
            current.append(line)
        elif current:
            out.append(current)
            current = []
    return out


def columns(line: str) -> int:
    return len(re.findall(r"(?<!\\)\|", line)) - 1


def test_markdown_summary(pyimclsts_result):
    text = render_markdown(pyimclsts_result)
    assert text.splitlines()[0].startswith("## ❌ IMC conformance: FAIL for 3 of 3 messages — pyimclsts 0.1.2.1")
    assert "| Message | Verdict | PASS | FAIL | IMPL_DEFINED |" in text
    announce = next(m for m in pyimclsts_result.messages if m.name == "Announce")
    counts = {v: sum(c.verdict.value == v for c in announce.cases) for v in ("PASS", "FAIL", "IMPL_DEFINED")}
    assert f"| Announce (151) | ❌ FAIL | {counts['PASS']} | {counts['FAIL']} | {counts['IMPL_DEFINED']} |" in text
    shown = sum(c.verdict.value in ("FAIL", "NON_STRICT", "INCONCLUSIVE") for c in pyimclsts_result.cases)
    assert f"<details><summary>{shown} failing, non-strict or inconclusive cases</summary>" in text
    assert "<code>imc/Announce/crc/header-timestamp/le</code>" in text
    assert f"and {shown - 50} more" in text
    assert text.count("| ❌ FAIL |") == 50 + sum(m.verdict == "FAIL" for m in pyimclsts_result.messages)


def test_markdown_escapes_table_cells(hostile_result):
    text = render_markdown(hostile_result)
    assert "<script>" not in text and "<img" not in text and "`tick`" not in text and "\x00" not in text
    causes, messages, failing = tables(text)
    for table in (causes, messages, failing):
        assert {columns(line) for line in table} == {columns(table[0])}
    assert columns(causes[0]) == 6 and columns(failing[0]) == 5
    row = next(line for line in failing if FAILING_CASE in line)
    assert "&lt;script&gt;alert(1)&lt;/script&gt;" in row and "a&#124;b" in row and "&#96;tick&#96;" in row


# --- HTML ---------------------------------------------------------------------------------------------------------

class Dom(HTMLParser):
    """Collects every start tag with its attributes, the text, and the legend entries per case section."""

    def __init__(self, text: str):
        super().__init__(convert_charrefs=True)
        self.tags: list[tuple[str, dict]] = []
        self.text: list[str] = []
        self.ranges: list[dict] = []  # legend entries: attributes, the enclosing case, the entry's text
        self.case = None
        self.open_range = None
        self.feed(text)
        self.close()

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        self.tags.append((tag, attrs))
        if tag == "section" and "data-case" in attrs:
            self.case = attrs["data-case"]
        if "data-field" in attrs:
            self.open_range = dict(attrs, case=self.case, text="")
            self.ranges.append(self.open_range)

    def handle_endtag(self, tag):
        if tag == "li":
            self.open_range = None

    def handle_data(self, data):
        self.text.append(data)
        if self.open_range is not None:
            self.open_range["text"] += data


def test_html_is_self_contained(broken_result):
    dom = Dom(render_html(broken_result))
    names = {tag for tag, _ in dom.tags}
    assert not names & {"script", "link", "img", "iframe", "object", "embed"}
    for _, attrs in dom.tags:
        for key in ("href", "src"):
            assert attrs.get(key) is None or attrs[key].startswith("#"), attrs


def test_html_escapes_implementation_text(hostile_result):
    html = render_html(hostile_result)
    dom = Dom(html)
    names = [tag for tag, _ in dom.tags]
    assert "script" not in names and "img" not in names
    assert not any(key.startswith("on") for _, attrs in dom.tags for key in attrs)
    text = "".join(dom.text)
    assert text.count("<script>alert(1)</script> <img src=x onerror=alert(2)>") >= 4  # title, header, note, detail...
    assert "&lt;script&gt;alert(1)&lt;/script&gt;" in html and "\x00" not in html and "\x1b" not in html


def test_html_marks_differing_bytes_by_field(broken_result):
    html = render_html(broken_result)
    dom = Dom(html)
    ranges = [r for r in dom.ranges if r["case"] == FAILING_CASE]
    # encode-be: range (float32 at 21-24) 0.0 -> 1.0 changes bytes 21-22; the CRC changes too.
    assert {"data-field": "LblRange.range", "data-start": "21", "data-end": "23"}.items() <= ranges[0].items()
    assert ranges[0]["text"] == "bytes 21–22 = LblRange.range"
    assert any(r["data-field"] == "footer.crc16" for r in ranges)
    assert '<mark class="r0" title="LblRange.range, byte 21">00</mark>' in html
    assert f"Failing cases ({sum(c.verdict is Verdict.FAIL for c in broken_result.cases)})" in "".join(dom.text)


def test_html_caps_detailed_failures(pyimclsts_result, monkeypatch):
    monkeypatch.setattr(html_module, "MAX_DETAILED", 5)
    dom = Dom(render_html(pyimclsts_result))
    assert sum(1 for tag, attrs in dom.tags if tag == "section" and "data-case" in attrs) == 5
    failing = sum(c.verdict is Verdict.FAIL for c in pyimclsts_result.cases)
    assert f"Showing the first 5 of {failing} failing cases" in "".join(dom.text)


def test_html_long_frames_show_rows_around_differences():
    expected = bytes(600)
    actual = expected[:500] + b"\x01" + expected[501:] + b"\x02"
    pair = html_module.frame_pair(expected.hex(), actual.hex(), (ByteDiff(500, 501, "X.data"),
                                                                 ByteDiff(600, 601, "beyond the expected frame")),
                                  ["encode-le"])
    offsets = [row.get("offset", "gap") for row in pair["actual"]["rows"]]
    assert offsets == ["0000", "0010", "gap", "01e0", "01f0", "0200", "gap", "0240", "0250"]
    marked = [m for row in pair["actual"]["rows"] if not row["gap"]
              for m in re.findall(r'<mark class="r\d" title="([^"]*)">(\w\w)</mark>', str(row["html"]))]
    assert marked == [("X.data, byte 500", "01"), ("beyond the expected frame, byte 600", "02")]
    assert len(str(pair["expected"]["rows"][-1]["html"]).split()) == 8  # the expected frame ends 8 bytes into that row


def chromium(*args: str, profile: Path) -> subprocess.CompletedProcess:
    argv = [str(CHROMIUM), "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
            "--disable-background-networking", "--disable-component-update", "--disable-sync",
            f"--user-data-dir={profile}", *args]
    done = subprocess.run(argv, capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr[-2000:]
    return done


@pytest.mark.skipif(not CHROMIUM.exists(), reason="needs Debian's chromium at /usr/bin/chromium (CI installs it)")
def test_html_report_in_headless_chromium(broken_result, tmp_path):
    page = tmp_path / "report.html"
    page.write_text(render_html(broken_result), encoding="utf-8")
    url = page.as_uri()
    dom = Dom(chromium("--dump-dom", url, profile=tmp_path / "profile-dom").stdout)
    assert any(attrs.get("data-case") == FAILING_CASE for _, attrs in dom.tags)
    assert FAILING_CASE in "".join(dom.text)
    legend = [r for r in dom.ranges if r["case"] == FAILING_CASE and r["data-field"] == "LblRange.range"]
    assert legend and all(r["text"].endswith("= LblRange.range") for r in legend)

    shot = tmp_path / "html-report.png"  # never into the checkout
    chromium(f"--screenshot={shot}", "--window-size=1400,2400", url, profile=tmp_path / "profile-shot")
    assert shot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert shot.stat().st_size > 10_000


# --- one escaping policy for every renderer --------------------------------------------------------------------

TRICKS = ("evil \u202eTEXT\u202c \u2066iso\u2069 \u200bzero \u061cmark \ufeffbom \u2028sep \ud800lone \U000e0041tag "
          "\x1b]0;title\x07 \r:skull: :white_check_mark: PASS [bold]markup[/bold] step:heartbeat:")
RAW_TRICKS = ("\u202e", "\u202c", "\u2066", "\u2069", "\u200b", "\u061c", "\ufeff", "\u2028", "\ud800", "\U000e0041",
              "\x1b", "\x07", "\r")


@pytest.fixture(scope="module")
def tricky_result(broken_result):
    """The broken run with bidirectional, invisible and emoji-code text wherever the implementation speaks."""
    doc = broken_result.to_dict()
    doc["implementation"] = doc["stderr"] = TRICKS
    doc["notes"] = [TRICKS]
    case = next(c for m in doc["messages"] for c in m["cases"] if c["id"] == FAILING_CASE)
    case["detail"] = TRICKS
    next(k for k in case["checks"] if k["verdict"] == "FAIL")["detail"] = TRICKS
    return RunResult.from_dict(doc)


def terminal_text(result) -> str:
    from imc_conformance.commands.output import terminal
    from imc_conformance.render.terminal import print_result

    console = terminal()
    with console.capture() as captured:
        print_result(result, console)
    return captured.get()


@pytest.mark.parametrize("render", [render_markdown, render_html, render_junit, terminal_text],
                         ids=["markdown", "html", "junit", "terminal"])
def test_every_renderer_shows_hidden_and_reordering_characters_as_escapes(tricky_result, render):
    text = render(tricky_result)
    assert not [c for c in RAW_TRICKS if c in text]
    assert "\\u202e" in text and "\\u2066" in text and "\\U000e0041" in text and "\\x1b" in text
    assert "💀" not in text and "💓" not in text  # emoji codes are text, never emoji


def test_the_terminal_interprets_no_emoji_code_and_no_markup(tricky_result):
    text = terminal_text(tricky_result)
    assert ":skull: :white_check_mark: PASS [bold]markup[/bold] step:heartbeat:" in text


def test_markdown_leaves_no_emoji_code_for_github_to_render(tricky_result):
    text = render_markdown(tricky_result)
    assert ":skull:" not in text and ":white" not in text and "&#58;skull&#58;" in text


def test_a_hostile_case_id_is_escaped_in_every_attribute_of_the_html(broken_result):
    doc = broken_result.to_dict()
    case = next(c for m in doc["messages"] for c in m["cases"] if c["id"] == FAILING_CASE)
    case["id"] = FAILING_CASE + "/evil\u202eTEXT\u2066"
    doc.pop("causes", None)
    text = render_html(RunResult.from_dict(doc))
    assert "\u202e" not in text and "\u2066" not in text
    assert f'data-case="{FAILING_CASE}/evil\\u202eTEXT\\u2066"' in text
