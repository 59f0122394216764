"""Where the corpus data lives, in a source checkout and in an installed package alike."""

from __future__ import annotations

from pathlib import Path

_HERE = Path(__file__).resolve().parent
# Installed: the vectors are package data next to this module; in a checkout they sit beside conformance/.
VECTORS = _HERE / "vectors" if (_HERE / "vectors").is_dir() else _HERE.parent / "vectors"
# The adapters (built-in ones, the starters, the C++ examples) and the adapter contract: package data when installed.
ADAPTERS = _HERE / "adapters" if (_HERE / "adapters").is_dir() else _HERE.parent / "adapters"
CONTRACT = ADAPTERS / "README.md"
STARTERS = ADAPTERS / "starters"
