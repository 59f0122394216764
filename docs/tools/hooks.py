"""MkDocs hook (mkdocs.yml ``hooks:``): the site is built from the reference pages as committed, so it shows what a
forge shows; a page whose generated part is stale stops the build, naming ``make reference`` (``reference.py``)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path


def _reference():
    spec = importlib.util.spec_from_file_location("docs_tools_reference", Path(__file__).with_name("reference.py"))
    module = importlib.util.module_from_spec(spec)
    before, sys.dont_write_bytecode = sys.dont_write_bytecode, True
    try:
        spec.loader.exec_module(module)
    finally:
        sys.dont_write_bytecode = before
    return module


def on_pre_build(config) -> None:
    """Stop the build on a stale reference page."""
    stale = _reference().stale()
    if stale:
        names = ", ".join(str(p.relative_to(Path(config["docs_dir"]).parent)) for p in stale)
        raise SystemExit(f"stale reference pages (run make reference): {names}")
