"""Where the corpus data lives, in a source checkout and in an installed package alike."""

from __future__ import annotations

from pathlib import Path

_HERE = Path(__file__).resolve().parent
# Installed: the vectors are package data next to this module; in a checkout they sit beside conformance/.
VECTORS = _HERE / "vectors" if (_HERE / "vectors").is_dir() else _HERE.parent / "vectors"
