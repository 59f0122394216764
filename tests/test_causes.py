"""Causes, not only cases: failures grouped by what broke them across messages (core.causes), in the result and at
the head of every report; `report --causes` on a saved result; shards merged keep them; an implementation without
errata gets the same groups."""

from __future__ import annotations

import json
import re
import xml.etree.ElementTree as ET

import pytest

from imc_conformance.cli import main
from imc_conformance.core.runner import run_cases
from imc_conformance.core.shards import merge
from imc_conformance.render.html import render_html
from imc_conformance.render.json_result import render_json
from imc_conformance.render.junit import render_junit
from imc_conformance.render.markdown import render_markdown
from imc_conformance.sessions.library import LibrarySession
from imc_conformance.suites.imc.mutants import CanonicalNan

MESSAGES = ("Announce", "LblRange", "TextMessage", "HistoricData")


@pytest.fixture(scope="module")
def chosen(cases):
    return [c for c in cases if c.group in MESSAGES]


@pytest.fixture(scope="module")
def pyimclsts_run(suite, chosen, pyimclsts_adapter):
    return run_cases(LibrarySession(pyimclsts_adapter, "pyimclsts"), suite, chosen, edition="imc-5.4.30",
                     adapter="pyimclsts")


def test_failures_are_grouped_by_rule_across_messages_and_match_the_errata(pyimclsts_run):
    causes = pyimclsts_run.cause_groups()
    grouped = [i for c in causes for i in c.cases]
    failing = [c.id for c in pyimclsts_run.cases if c.verdict.value in ("FAIL", "NON_STRICT", "CRASH")]
    assert sorted(grouped) == sorted(failing) and len(grouped) == len(set(grouped))
    assert [len(c.cases) for c in causes] == sorted((len(c.cases) for c in causes), reverse=True)
    by_key = {c.key: c for c in causes}
    crc = by_key["accepts/rule:crc"]
    assert crc.title == "accepts what breaks rule crc" and set(crc.messages) == set(MESSAGES)
    assert dict(crc.errata)["P1"] == len(crc.cases)  # every case of it is pyimclsts's erratum P1 (no CRC check)
    assert dict(by_key["accepts/rule:unknown-id"].errata) == {"P3": len(by_key["accepts/rule:unknown-id"].cases)}
    for cause in causes:  # every group is explained by the errata, each of its cases by one at least
        assert cause.errata and max(n for _, n in cause.errata) <= len(cause.cases)


def test_an_implementation_without_errata_gets_the_same_groups(suite, chosen, pyimclsts_adapter, pyimclsts_run):
    bare = run_cases(LibrarySession(pyimclsts_adapter, "pyimclsts"), suite, chosen, edition="imc-5.4.30",
                     adapter="pyimclsts", errata="no-such-implementation")
    assert [(c.key, c.cases) for c in bare.cause_groups()] == [(c.key, c.cases) for c in pyimclsts_run.cause_groups()]
    assert all(not c.errata for c in bare.cause_groups())


def test_a_seeded_bug_in_values_is_one_cause_across_messages(suite, cases, defs):
    """The mutant that answers every NaN as the default NaN: its failures are the valid cases pinning a NaN's bits, in
    many messages and two value classes, and they are one cause."""
    result = run_cases(LibrarySession(CanonicalNan(defs), "canonical-nan"), suite, cases, edition="imc-5.4.30",
                       adapter="canonical-nan")
    (cause,) = result.cause_groups()
    assert cause.key == "fails/decode+roundtrip/valid"  # the key stays what waivers by cause name
    # the title says what differs: the value classes, the one value answered in their place, the fields
    assert cause.title.startswith("decode+roundtrip fails on valid input: class nan-payload or negative-nan; "
                                  "answered as 'nan'; in ")
    assert "fields)" in cause.title
    assert len(cause.messages) > 5 and all("nan" in case_id.rsplit("/", 1)[1] for case_id in cause.cases)


def test_a_cause_of_refusals_names_the_types_its_cases_hold_and_the_words_of_the_refusal(pyimclsts_run):
    """pyimclsts refuses valid frames whose HistoricData list holds a RemoteCommand: the title says so."""
    cause = next(c for c in pyimclsts_run.cause_groups() if c.key.startswith("fails/"))
    assert "holding HistoricData" in cause.title, cause.title
    assert "refused: pyimclsts.network.unpack: ValueError: Cannot have" in cause.title, cause.title


def test_every_report_opens_with_the_causes(pyimclsts_run):
    first = pyimclsts_run.cause_groups()[0]
    markdown = render_markdown(pyimclsts_run)
    assert markdown.index("**Causes**") < markdown.index("| Message |")
    assert f"| 1 | {first.title} | {len(first.cases)} |" in markdown
    html = render_html(pyimclsts_run)
    assert html.index('id="causes"') < html.index('id="matrix"')
    assert re.search(rf'<li id="cause-1" data-cause="{re.escape(first.key)}">', html)
    assert 'href="#case-1"' in html  # a cause's cases link to their detail where the report shows it
    doc = json.loads(render_json(pyimclsts_run))
    assert list(doc).index("causes") < list(doc).index("messages")
    assert doc["causes"][0] == first.to_dict()
    root = ET.fromstring(render_junit(pyimclsts_run).encode())
    assert any(p.get("name") == "cause" and p.get("value").startswith(first.title) for p in root.iter("property"))
    failure = root.find(f".//testcase[@name='{first.cases[0]}']/failure")
    assert f"cause: {first.title}" in failure.text


def test_report_causes_on_a_saved_result(pyimclsts_run, tmp_path, capsys):
    saved = tmp_path / "r.json"
    saved.write_text(render_json(pyimclsts_run), encoding="utf-8")
    assert main(["report", str(saved), "--causes"]) == pyimclsts_run.exit_code()
    out = capsys.readouterr().out
    causes = pyimclsts_run.cause_groups()
    assert out.startswith(f"Causes: {sum(len(c.cases) for c in causes)} failing or non-strict cases, {len(causes)} causes")
    assert all(case_id in out for c in causes for case_id in c.cases)
    assert "┃ message" not in out  # only the causes


def test_merged_shards_keep_the_groups_of_the_whole_run(suite, chosen, pyimclsts_adapter, pyimclsts_run):
    from imc_conformance.core.cases import shard_of
    from imc_conformance.core.results import Provenance

    made = Provenance(tool="imc-conformance test", corpus="sha256:0", selection={"cases": len(chosen)},
                      errata="pyimclsts", waivers=None, command=["run"])
    parts = []
    for k in (1, 2):
        result = run_cases(LibrarySession(pyimclsts_adapter, "pyimclsts"), suite,
                           [c for c in chosen if shard_of(c.id, 2) == k], edition="imc-5.4.30", adapter="pyimclsts")
        result.shard, result.provenance = (k, 2), made
        parts.append(result)
    merged = merge(parts, [g.name for g in suite.groups], {c.id: i for i, c in enumerate(chosen)})
    assert [c.to_dict() for c in merged.cause_groups()] == [c.to_dict() for c in pyimclsts_run.cause_groups()]
