"""The suites: one package each (``imc``, ``ros_acomms``), found by listing this package.

Each suite package has ``load(folder=None) -> Suite``: the suite over its packaged data, or over a data
folder given instead (``--vectors``), whose definitions, cases and errata then apply.
"""

from __future__ import annotations

import importlib
import pkgutil
from functools import cache
from pathlib import Path


def names() -> list[str]:
    """The installed suites' names, the default (imc) first."""
    found = sorted(m.name for m in pkgutil.iter_modules(__path__) if m.ispkg)
    return sorted(found, key=lambda n: n != "imc")


@cache
def load_suite(name: str, folder: Path | None = None):
    """The suite ``name`` (a ``core.suite.Suite``) over its packaged data, or over ``folder``; raises LookupError for
    an unknown name."""
    if name not in names():
        raise LookupError(f"unknown suite {name!r} (suites: {', '.join(names())})")
    return importlib.import_module(f"{__name__}.{name}").load(folder)
