"""A reference IMC node, sans-IO: the seeds' behaviour over a simulated acoustic channel and fake Iridium and
SMS gateways, the broken behaviours that show each rule is caught, and the variants that take another reading the
seeds allow. ``ReferenceNode`` is imported when first used: registering ``serve`` on the command line needs only
``BREAKS`` and ``VARIANTS``."""

from .breaks import BREAKS, VARIANTS

__all__ = ["BREAKS", "ReferenceNode", "VARIANTS"]


def __getattr__(name: str):
    if name == "ReferenceNode":
        from .node import ReferenceNode
        return ReferenceNode
    raise AttributeError(name)
