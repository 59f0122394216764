"""The manual as a reader meets it, wherever they read it: every count of scenarios, robustness probes and vector
cases a page gives is the corpus's (computed from the corpus, so a scenario added fails the page that still says the
old number), every session IMC id a page gives is the one ``run --help`` gives, and no page holds syntax only the
documentation site renders (a forge shows the raw Markdown: ``??? note`` lines, ``: definition`` lists).

A figure of an earlier measurement says so (``63 scenarios when measured``) and is not compared."""

from __future__ import annotations

import re
from collections import Counter
from functools import cache
from pathlib import Path

from imc_conformance.core.cases import expectation
from imc_conformance.files import open_corpus

CHECKOUT = Path(__file__).resolve().parents[1]
PAGES = [*sorted((CHECKOUT / "docs").rglob("*.md")), CHECKOUT / "README.md", CHECKOUT / "adapters" / "README.md",
         *sorted((CHECKOUT / "adapters" / "starters").glob("*/README.md"))]
NUMBER = r"(?<![\d.,])(\d{1,3}(?:,\d{3})+|\d+)"
FIGURE = re.compile(NUMBER + r" (?:IMC |ros_acomms )?(scenarios|robustness probes|vector cases)\b(?! when measured)")
CORPUS = re.compile(NUMBER + r" (?:vector )?cases over " + NUMBER + r" (messages|types)\b(?! when measured)")
SITE_ONLY = re.compile(r"^(?:\?\?\?\+? |!!! |=== \"|:   |\{: |--8<--)", re.M)


def prose(path: Path) -> str:
    """A page without its fenced code blocks (commands and their output, which the docs tests run)."""
    out, fenced = [], False
    for line in path.read_text(encoding="utf-8").split("\n"):
        if line.lstrip().startswith("```"):
            fenced = not fenced
        elif not fenced:
            out.append(line)
    return "\n".join(out)


@cache
def corpus() -> dict:
    """What the pages may say of the corpus: the counts of each suite's scenarios, robustness probes and vector cases
    (all of them, and those of each edition), and (vector cases, groups) per suite."""
    out = {"scenarios": set(), "robustness probes": set(), "vector cases": set(), "over": set()}
    for name in ("imc", "ros_acomms"):
        suite, cases = open_corpus(name)
        kinds = Counter(c.kind for c in cases)
        vectors = [c for c in cases if c.kind == "vector"]
        out["scenarios"].add(kinds["scenario"])
        out["robustness probes"].add(kinds["robustness"])
        out["vector cases"] |= {len(vectors), *(sum(expectation(c.data, e) is not None for c in vectors)
                                                for e in suite.editions)}
        out["over"].add((len(vectors), len({c.group for c in vectors})))
    return out


def number(text: str) -> int:
    return int(text.replace(",", ""))


def stale_figures(text: str) -> list[tuple[str, list]]:
    """Each figure of ``text`` the corpus does not give, with the ones it gives."""
    figures, wrong = corpus(), []
    for m in FIGURE.finditer(text):
        if number(m[1]) not in figures[m[2]]:
            wrong.append((m[0], sorted(figures[m[2]])))
    for m in CORPUS.finditer(text):
        if (number(m[1]), number(m[2])) not in figures["over"]:
            wrong.append((m[0], sorted(figures["over"])))
    return wrong


def test_every_corpus_figure_a_page_gives_is_the_corpus():
    wrong = [f"{path.relative_to(CHECKOUT)}: {found!r} (the corpus: {known})"
             for path in PAGES for found, known in stale_figures(prose(path))]
    assert wrong == []


def test_a_stale_scenario_count_is_found(tmp_path):
    page = tmp_path / "page.md"
    page.write_text(f"The whole set ({max(corpus()['scenarios']) + 1} scenarios) against a node, "
                    "(63 scenarios when measured).\n\n```console\n$ run\n9 scenarios\n```\n", encoding="utf-8")
    found = [found for found, _ in stale_figures(prose(page))]
    assert found == [f"{max(corpus()['scenarios']) + 1} scenarios"]


def test_every_session_id_a_page_gives_is_the_one_of_the_help():
    from imc_conformance.cli import build_parser

    parser = build_parser(["run"])
    run = next(a for a in parser._subparsers._group_actions[0].choices["run"]._actions if "--src" in a.option_strings)
    bounds = re.search(r"(0x[0-9A-F]{4})-(0x[0-9A-F]{4})", run.help).groups()
    said = {f"{path.relative_to(CHECKOUT)}: {found}" for path in PAGES
            for found in re.findall(r"0x4C[0-9A-F]{2}", prose(path)) if found not in bounds}
    assert said == set(), f"the session's id is one of {bounds[0]}-{bounds[1]} (run --help)"


def test_no_page_holds_syntax_only_the_site_renders():
    found = [f"{path.relative_to(CHECKOUT)}: {m[0]!r}" for path in PAGES for m in SITE_ONLY.finditer(prose(path))]
    assert found == []
