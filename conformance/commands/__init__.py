"""The command line's commands, one module each (``add(subparsers)`` registers its options; its command function
imports what it needs when it runs), and each suite's own commands (``suites/<name>/commands.py``)."""

from __future__ import annotations

import importlib

from ..suites import names as suite_names

COMMANDS = ("run", "listing", "report", "generate", "pcap", "watch")  # in the order --help lists them


def add_all(sub) -> None:
    for name in COMMANDS:
        importlib.import_module(f"{__name__}.{name}").add(sub)
    root = __name__.rpartition(".")[0]
    for suite in suite_names():
        name = f"{root}.suites.{suite}.commands"
        try:
            module = importlib.import_module(name)
        except ModuleNotFoundError as exc:
            if exc.name != name:
                raise
            continue
        module.add(sub)
