"""Counts in words: ``1 frame``, ``2 frames``, the one rule every report line and note follows."""

from __future__ import annotations


def counted(n: int, noun: str, grouped: bool = False) -> str:
    """``n`` with its noun in the right number; ``grouped`` writes thousands apart (``14,615 frames``)."""
    return (f"{n:,}" if grouped else str(n)) + " " + (noun if n == 1 else noun + "s")
