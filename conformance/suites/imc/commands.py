"""The IMC suite's own commands: ``serve``, the reference node, and ``gateway``, the Iridium/SMS gateway stand-in
(registered without loading the suite)."""

from __future__ import annotations

NAMES = ("serve", "gateway")


def add(sub) -> None:
    from .node.gateway_cli import add_command as add_gateway
    from .node.serve import add_command
    add_command(sub)
    add_gateway(sub)
