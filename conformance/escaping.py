"""How text from outside (an implementation, a node, a capture) is shown: the one escaping policy of every output.
Its own module, light, so that the command line can escape an error message without importing the renderers."""

from __future__ import annotations

import re

# The one policy for what an implementation, a node or a capture says, whatever the output (terminal, JSON aside,
# Markdown, HTML, JUnit): every character that could drive a terminal, reorder or hide text, forge a line or break
# XML is shown as an escape (``\x1b``, ``\u202e``), and nothing else is changed: controls (C0 but tab and newline,
# DEL, C1), the Arabic letter mark, zero-width and bidirectional marks, embeddings, overrides and isolates, line and
# paragraph separators, invisible operators, the byte order mark, interlinear annotations, lone surrogates,
# non-characters XML forbids and tag characters. Each renderer then escapes its own markup; the terminal also
# shows newlines as escapes (one line of a log per item).
_UNSAFE = "\x00-\x08\x0b-\x1f\x7f-\x9f\u061c\u200b-\u200f\u2028-\u202e\u2060-\u206f\ufeff\ufff9-\ufffb\ufffe\uffff" \
          "\ud800-\udfff\U000e0000-\U000e007f"
_UNSAFE_TEXT = re.compile(f"[{_UNSAFE}]")
_UNSAFE_LINE = re.compile(f"[{_UNSAFE}\n]")


def _escape(m: re.Match) -> str:
    code = ord(m[0])
    return f"\\x{code:02x}" if code < 0x100 else f"\\u{code:04x}" if code < 0x10000 else f"\\U{code:08x}"


def clean(text: str | None) -> str:
    """Implementation text for a report (Markdown, HTML, JUnit): the unsafe characters shown as escapes, lines
    and tabs kept."""
    return _UNSAFE_TEXT.sub(_escape, text or "")


def printable(text: str | None) -> str:
    """Implementation text for a terminal or a log line: as ``clean``, and newlines shown as escapes too, so that
    it can neither drive the terminal nor forge log lines."""
    return _UNSAFE_LINE.sub(_escape, text or "")
