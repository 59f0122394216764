"""The scenario case kind: behaviour over a live link, written as data and run by a sans-IO engine."""

from .conductor import Conductor, Outgoing
from .kind import ScenarioKind
from .machine import Machine, Program
from .wire import Addressing, Composed, Parsed, Wire

__all__ = ["Addressing", "Composed", "Conductor", "Machine", "Outgoing", "Parsed", "Program", "ScenarioKind", "Wire"]
