"""The suite's cache folder for downloads and memos: ``$IMC_CONFORMANCE_CACHE``, else ``~/.cache/imc-conformance``.

Nothing in it is needed for correctness: deleting it only costs a download or a re-check.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path


def cache_dir() -> Path:
    root = os.environ.get("IMC_CONFORMANCE_CACHE") or Path.home() / ".cache" / "imc-conformance"
    path = Path(root)
    path.mkdir(parents=True, exist_ok=True)
    return path


def remembered(kind: str, *parts: bytes) -> tuple[bool, callable]:
    """Whether a check of ``kind`` already succeeded on exactly these bytes, and a function recording success.

    Used for slow, pure checks of files (e.g. a JSON Schema over a 16 MB corpus). An unwritable cache only
    means the check runs every time.
    """
    digest = hashlib.sha256()
    for part in parts:
        digest.update(hashlib.sha256(part).digest())
    try:
        marker = cache_dir() / "checked" / kind / digest.hexdigest()
    except OSError:
        return False, lambda: None

    def record() -> None:
        try:
            marker.parent.mkdir(parents=True, exist_ok=True)
            marker.touch()
        except OSError:
            pass
    return marker.exists(), record
