"""The robustness case kind: the target must survive every corpus frame and a burst of garbage."""

from .kind import RobustnessKind

__all__ = ["RobustnessKind"]
