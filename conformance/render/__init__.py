"""Report renderers: each takes a ``RunResult`` and returns the report as a string (the CLI writes files)."""

from __future__ import annotations

from .html import render_html
from .json_result import render_json
from .junit import render_junit
from .markdown import render_markdown

RENDERERS = {"json": render_json, "junit": render_junit, "markdown": render_markdown, "html": render_html}

__all__ = ["RENDERERS", "render_html", "render_json", "render_junit", "render_markdown"]
