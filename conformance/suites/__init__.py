"""The suites: one package each (``imc``, ``ros_acomms``), found by listing this package.

Each suite package has ``load(folder=None) -> Suite``: the suite over its packaged data, or over a data
folder given instead (``--vectors``), whose definitions, cases and errata then apply. A package may also offer
variants of its suite over other data it builds itself (``VARIANTS``: name -> one line of help, and
``load_variant(name, folder=None)``); ``--suite`` takes their names too.
"""

from __future__ import annotations

import importlib
import pkgutil
from functools import cache
from pathlib import Path


@cache
def packages() -> tuple[str, ...]:
    """The installed suite packages' names, the default (imc) first."""
    found = sorted(m.name for m in pkgutil.iter_modules(__path__) if m.ispkg)
    return tuple(sorted(found, key=lambda n: n != "imc"))


@cache
def variants() -> dict[str, tuple[str, str]]:
    """Every variant a suite package offers: name -> (package, help)."""
    out = {}
    for package in packages():
        for name, text in getattr(importlib.import_module(f"{__name__}.{package}"), "VARIANTS", {}).items():
            out[name] = (package, text)
    return out


def names() -> list[str]:
    """Every name ``--suite`` takes: the suites (the default first), then their variants."""
    return [*packages(), *variants()]


@cache
def load_suite(name: str, folder: Path | None = None):
    """The suite ``name`` (a ``core.suite.Suite``) over its packaged data, or over ``folder``; raises LookupError for
    an unknown name, ValueError for a variant whose data cannot be built."""
    if name in variants():
        return importlib.import_module(f"{__name__}.{variants()[name][0]}").load_variant(name, folder)
    if name not in packages():
        raise LookupError(f"unknown suite {name!r} (suites: {', '.join(names())})")
    return importlib.import_module(f"{__name__}.{name}").load(folder)
