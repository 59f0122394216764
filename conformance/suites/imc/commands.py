"""The IMC suite's own command: ``serve``, the reference node (registered without loading the suite)."""

from __future__ import annotations

NAMES = ("serve",)


def add(sub) -> None:
    from .node.serve import add_command
    add_command(sub)
