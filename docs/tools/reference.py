"""The reference pages' generated parts (``make reference`` writes them; ``--check`` says which page is stale).

A page of ``docs/reference`` holds a marker line ``<!-- generated: NAME ... -->``: everything after it is the part
NAME, written into the page so that a forge shows it as the site does. Every part comes from what the project ships:
the command line's argument parsers (every command and option), the adapter contract (``adapters/README.md``), the
JSON Schemas, the errata, and the tables ``imc-conformance generate`` writes from the corpus data (rule provenance,
behavioural coverage with the ambiguity register, corpus coverage). ``tests/test_docs.py`` fails when a page is not
what this writes, and the site's build (``hooks.py``) stops on a stale page.

Written by a script in the repository rather than a plug-in: the argparse plug-ins for MkDocs on PyPI are young or for
another formatter (mkdocs-argparse has one 0.0.1 release, mkdocs-rich-argparse documents rich-argparse parsers), and
walking the parsers, the commands in ``commands.COMMANDS`` order then each suite's own, takes a page of code and no
dependency."""

from __future__ import annotations

import argparse
import json
import os
import re
import sys
from pathlib import Path

from imc_conformance import commands
from imc_conformance.cli import build_parser

ROOT = Path(__file__).resolve().parents[2]
VECTORS = ROOT / "vectors"
MARKER = re.compile(r"^<!-- generated: ([\w-]+)(?: \(.*\))? -->$", re.MULTILINE)


DOCS = ROOT / "docs"
PAGES = DOCS / "reference"
NOTE = "make reference writes what follows from the project's files: edit those, not this page"


def render(text: str, where: str = "page") -> str:
    """The page with its generated part written after its marker; an unknown marker is an error."""
    match = MARKER.search(text)
    if match is None:
        return text
    name = match.group(1)
    if name not in PARTS:
        raise ValueError(f"{where}: no generated part named {name!r} (known: {', '.join(PARTS)})")
    return f"{text[:match.start()]}<!-- generated: {name} ({NOTE}) -->\n\n{PARTS[name]().strip()}\n"


def pages() -> list[Path]:
    """The pages that hold a generated part."""
    return [p for p in sorted(PAGES.glob("*.md")) if MARKER.search(p.read_text(encoding="utf-8"))]


def stale() -> list[Path]:
    """The pages whose generated part is not what ``render`` writes today."""
    out = []
    for page in pages():
        text = page.read_text(encoding="utf-8")
        if render(text, page.name) != text:
            out.append(page)
    return out


def main(argv: list[str] | None = None) -> int:
    """``reference.py [--check]``: write every generated part, or (``--check``) exit 1 naming the stale pages."""
    check = (argv if argv is not None else sys.argv[1:]) == ["--check"]
    changed = stale()
    for page in changed:
        name = page.relative_to(ROOT) if ROOT in page.parents else page
        if check:
            print(f"{name}: stale (make reference writes it)")
        else:
            page.write_text(render(page.read_text(encoding="utf-8"), str(name)), encoding="utf-8")
            print(f"{name}: written")
    return 1 if check and changed else 0


# --- the command line ----------------------------------------------------------------------------------------------

def cli_reference() -> str:
    """Every command of ``imc-conformance`` with its usage and every option, from the parsers themselves."""
    previous = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = "118"  # argparse wraps usage lines to the terminal's width: the page is the same anywhere
    try:
        return _cli_reference()
    finally:
        if previous is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = previous


def _cli_reference() -> str:
    parser = build_parser()
    out = [f"```text\n{parser.format_usage().strip()}\n```", "", _escape(parser.description or ""), ""]
    out += _options(parser)
    if parser.epilog:
        out += ["", _escape(parser.epilog)]
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    helps = {c.dest: c.help for c in sub._choices_actions}
    order = [*commands.COMMANDS, *(name for name in sub.choices if name not in commands.COMMANDS)]
    for name in order:
        command = sub.choices[name]
        out += ["", f"## `{name}`", ""]
        if helps.get(name):
            out += [_escape(helps[name]), ""]
        out += [f"```text\n{command.format_usage().strip()}\n```", ""]
        if command.description and command.description != helps.get(name):
            out += [_escape(command.description), ""]
        out += _options(command)
        if command.epilog:
            out += ["", _escape(command.epilog)]
    return "\n".join(out) + "\n"


def _options(parser: argparse.ArgumentParser) -> list[str]:
    formatter = parser._get_formatter()
    out = []
    for group in parser._action_groups:
        actions = [a for a in group._group_actions
                   if a.help is not argparse.SUPPRESS and not isinstance(a, (argparse._HelpAction, argparse._SubParsersAction))]
        if not actions:
            continue
        out += ["", f"**{_escape(group.title)}**" if group.title else "", ""]
        for action in actions:
            names = ", ".join(f"`{s}`" for s in action.option_strings) or f"`{action.metavar or action.dest}`"
            shape = formatter._format_args(action, action.dest.upper()) if action.nargs != 0 else ""
            if shape and action.option_strings:
                names += f" `{shape}`"
            text = _escape(formatter._expand_help(action)) if action.help else ""
            if action.choices and "{" not in shape and action.option_strings:
                text += " (one of: " + ", ".join(f"`{c}`" for c in action.choices) + ")"
            out.append(f"- {names}: {text}".rstrip(": "))
    return out


def _escape(text: str) -> str:
    """Help text is plain text: nothing in it is Markdown markup."""
    return re.sub(r"([\\`*_\[\]<>|#])", r"\\\1", " ".join(text.split()))


# --- the adapter contract ------------------------------------------------------------------------------------------

def adapter_contract() -> str:
    """``adapters/README.md`` one heading level down, its links into the repository shown as paths."""
    text = (ROOT / "adapters" / "README.md").read_text(encoding="utf-8")
    text = re.sub(r"^# .*\n", "", text, count=1)
    text = re.sub(r"^(#+) ", r"#\1 ", text, flags=re.MULTILINE)

    def link(match: re.Match) -> str:
        label, target = match.groups()
        if target.startswith(("#", "http://", "https://")):
            return match.group(0)
        path = f"`adapters/{target}`"
        return path if label.strip("`") == target else f"{label} ({path})"
    return re.sub(r"\[([^\]]+)\]\(([^)\s]+)\)", link, text)


# --- the corpus data -----------------------------------------------------------------------------------------------

def schemas() -> str:
    """Every JSON Schema of ``vectors/schema``, with its title and description, and its text folded."""
    out = []
    for path in sorted((VECTORS / "schema").glob("*.schema.json")):
        doc = json.loads(path.read_text(encoding="utf-8"))
        out += [f"## `{path.name}`", "", f"**{_escape(doc.get('title', ''))}**. {_escape(doc.get('description', ''))}", "",
                '<details markdown="1"><summary>The schema</summary>', "", "```json",
                *path.read_text(encoding="utf-8").rstrip("\n").split("\n"), "```", "", "</details>", ""]
    return "\n".join(out)


def errata() -> str:
    """Every erratum of each suite, field by field, as ``errata.json`` holds it."""
    out = []
    for suite in ("imc", "ros_acomms"):
        out += [f"### {suite}", ""]
        for entry in json.loads((VECTORS / suite / "errata.json").read_text(encoding="utf-8"))["errata"]:
            out += [f"#### {entry['id']}", ""]
            for key, value in entry.items():
                if key == "id":
                    continue
                shown = _escape(value) if isinstance(value, str) else f"`{_escape(json.dumps(value, ensure_ascii=False))}`"
                out.append(f"- **{key}**: {shown}")
            out.append("")
    return "\n".join(out)


def _generated_table(name: str) -> str:
    """The Markdown ``imc-conformance generate`` writes beside each suite's corpus, one heading level down."""
    out = []
    for suite in ("imc", "ros_acomms"):
        text = (VECTORS / suite / name).read_text(encoding="utf-8")
        out.append(re.sub(r"^(#+) ", r"#\1 ", text, flags=re.MULTILINE))
    return "\n\n".join(out)


PARTS = {
    "cli": cli_reference,
    "adapter-contract": adapter_contract,
    "schemas": schemas,
    "errata": errata,
    "provenance": lambda: _generated_table("provenance.md"),
    "behaviour-coverage": lambda: _generated_table("behaviour-coverage.md"),
    "coverage": lambda: _generated_table("coverage.md"),
}


if __name__ == "__main__":
    sys.exit(main())
