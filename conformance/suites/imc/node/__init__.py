"""A reference IMC node, sans-IO: the seeds' behaviour over a simulated acoustic channel and fake Iridium and
SMS gateways, and the broken behaviours that show each rule is caught. ``ReferenceNode`` is imported when first
used: registering ``serve`` on the command line needs only ``BREAKS``."""

from .breaks import BREAKS

__all__ = ["BREAKS", "ReferenceNode"]


def __getattr__(name: str):
    if name == "ReferenceNode":
        from .node import ReferenceNode
        return ReferenceNode
    raise AttributeError(name)
