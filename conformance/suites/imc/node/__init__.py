"""A reference IMC node, sans-IO: the seeds' behaviour over a simulated acoustic channel and fake Iridium and
SMS gateways, and the broken behaviours that show each rule is caught."""

from .breaks import BREAKS
from .node import ReferenceNode

__all__ = ["BREAKS", "ReferenceNode"]
