"""What a library adapter raises: the contract between the runner and an implementation under test.

A library adapter is any object with ``hello() -> dict``, ``encode(suite, message, encoding) -> bytes``
and ``decode(suite, frame, **params) -> dict`` (messages in the suite's decoded form; ``params`` are the
suite's, e.g. a ROS ``type``), and, where a suite checks definitions, ``describe(suite, **params) -> dict``.
A handler of a suite's services (run by its scenarios) has ``setup(suite, service, state)``, ``call(suite,
service, request) -> dict`` (the response) and ``publish(suite, type, message)``.
It refuses an input by raising ``Rejected``; it declares a capability absent by raising ``Unsupported``.
Any other exception is an adapter error, never a pass.
"""

from __future__ import annotations


class Rejected(Exception):
    """The implementation refused the input; ``rule`` names the corpus rule it reported, if it knows."""

    def __init__(self, reason: str, rule: str | None = None):
        super().__init__(reason)
        self.reason, self.rule = reason, rule


class Unsupported(Exception):
    """The implementation lacks this capability (an operation, a byte order, a message)."""


def installed_version(module) -> str:
    """The version of the distribution that installed ``module`` (a top-level package): from the name of the
    ``NAME-VERSION.dist-info`` folder an installer writes beside it, else from ``importlib.metadata``. Read so first
    because importing and searching ``importlib.metadata`` costs more than the rest of a one-message run's start."""
    import os

    root, prefix = os.path.dirname(os.path.dirname(module.__file__)), module.__name__.lower() + "-"
    for entry in os.listdir(root):
        found = entry[len(prefix):-len(".dist-info")]
        if entry.lower().startswith(prefix) and entry.endswith(".dist-info") and found and "-" not in found:
            return found
    from importlib.metadata import version

    return version(module.__name__)
