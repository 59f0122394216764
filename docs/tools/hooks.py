"""MkDocs hook (mkdocs.yml ``hooks:``): the reference pages' generated parts, made when the site is built.

A page holds a marker line ``<!-- generated: NAME -->`` where the part NAME goes. Every part comes from what the
project ships: the command line's argument parsers (every command and option, so a renamed or added option is on the
site at the next build without anyone editing a page), the adapter contract (``adapters/README.md``), the JSON
Schemas, the errata, and the tables ``imc-conformance generate`` writes from the corpus data (rule provenance,
behavioural coverage with the ambiguity register, corpus coverage). Nothing is written into the checkout.

A hook in the repository rather than a plug-in (MkDocs runs it with the build: nothing generated is ever committed,
so nothing can go stale): the argparse plug-ins for MkDocs on PyPI are young or for another formatter (mkdocs-argparse
has one 0.0.1 release, mkdocs-rich-argparse documents rich-argparse parsers), and argparse-help-markdown writes a
file to commit (with cog); walking the parsers, the commands in ``commands.COMMANDS`` order then each suite's own,
takes a page of code and no dependency beyond MkDocs itself."""

from __future__ import annotations

import argparse
import json
import re
from pathlib import Path

from imc_conformance import commands
from imc_conformance.cli import build_parser

ROOT = Path(__file__).resolve().parents[2]
VECTORS = ROOT / "vectors"
MARKER = re.compile(r"^<!-- generated: ([\w-]+) -->$", re.MULTILINE)


def on_page_markdown(markdown: str, page, config, files) -> str:
    """Replace each marker with its generated part; an unknown marker stops the build."""
    def part(match: re.Match) -> str:
        name = match.group(1)
        if name not in PARTS:
            raise ValueError(f"{page.file.src_uri}: no generated part named {name!r} (known: {', '.join(PARTS)})")
        return PARTS[name]()
    return MARKER.sub(part, markdown)


def on_config(config):
    """The site is built from the checkout's own files: watch them in ``mkdocs serve`` too."""
    for path in (ROOT / "conformance" / "commands", ROOT / "adapters" / "README.md", VECTORS):
        config.watch.append(str(path))
    return config


# --- the command line ----------------------------------------------------------------------------------------------

def cli_reference() -> str:
    """Every command of ``imc-conformance`` with its usage and every option, from the parsers themselves."""
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
                f'??? note "The schema"', "", "    ```json",
                *("    " + line for line in path.read_text(encoding="utf-8").rstrip("\n").split("\n")), "    ```", ""]
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
