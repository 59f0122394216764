"""The command line's commands, one module each (``add(subparsers)`` registers its options; its command function
imports what it needs when it runs), and each suite's own commands (``suites/<name>/commands.py``, naming them in
``NAMES``). Only the command asked for is registered (a run never pays for building the others' options)."""

from __future__ import annotations

import importlib

from ..suites import packages as suite_packages

COMMANDS = {"run": "run", "list": "listing", "report": "report", "generate": "generate", "pcap": "pcap",
            "log": "log", "watch": "watch", "relay": "relay", "fuzz": "fuzz", "mutants": "mutants",
            "matrix": "matrix", "adapter-check": "adapter_check", "adapter-kit": "adapter_kit"}  # command -> its module, in the order --help lists them


def suite_commands() -> dict[str, object]:
    """Each suite's own commands: name -> the module that adds it."""
    root = __name__.rpartition(".")[0]
    out = {}
    for suite in suite_packages():
        name = f"{root}.suites.{suite}.commands"
        try:
            module = importlib.import_module(name)
        except ModuleNotFoundError as exc:
            if exc.name != name:
                raise
            continue
        out.update(dict.fromkeys(module.NAMES, module))
    return out


def add(sub, wanted: str | None) -> None:
    """Register the command ``wanted`` (None, or a name no command has: every command, for the help)."""
    if wanted in COMMANDS:
        importlib.import_module(f"{__name__}.{COMMANDS[wanted]}").add(sub)
        return
    for module in COMMANDS.values():
        importlib.import_module(f"{__name__}.{module}").add(sub)
    for module in dict.fromkeys(suite_commands().values()):
        module.add(sub)
