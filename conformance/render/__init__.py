"""Report renderers: each takes a ``RunResult`` and returns the report as a string (the CLI writes files).

``RENDERERS`` maps a format to its renderer, importing the renderer's module when it is first asked for: a run that
writes no HTML report never imports jinja2, and importing this package (or ``render.common``'s escaping) costs
nothing."""

from __future__ import annotations

import importlib
from collections.abc import Mapping

_MODULES = {"json": "json_result", "junit": "junit", "markdown": "markdown", "html": "html"}


class _Renderers(Mapping):
    def __getitem__(self, fmt: str):
        module = importlib.import_module(f"{__name__}.{_MODULES[fmt]}")
        return getattr(module, f"render_{fmt}")

    def __iter__(self):
        return iter(_MODULES)

    def __len__(self) -> int:
        return len(_MODULES)


RENDERERS = _Renderers()

__all__ = ["RENDERERS"]
