"""The types of the command line's numeric options, with the bounds of ``limits``: what a command accepts is
what the readers of its results accept back (a recording of a run reads back with the settings it was made with)."""

from __future__ import annotations

import argparse
import math

from .limits import STARTUP_MAX, TIME_SCALE_MAX


def bounded(top: float | None, what: str = "number of seconds"):
    """An argparse type: a positive, finite ``what`` no larger than ``top`` (None: unbounded)."""
    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a {what}") from None
        if not math.isfinite(value) or value <= 0 or (top is not None and value > top):
            limit = f", at most {top:g}" if top is not None else ""
            raise argparse.ArgumentTypeError(f"{text!r}: give a positive, finite {what}{limit}")
        return value
    return parse


positive_seconds = bounded(None)
startup_seconds = bounded(STARTUP_MAX)
time_scale = bounded(TIME_SCALE_MAX, "factor")


def megabytes(text: str) -> int:
    if not text.isdigit():
        raise argparse.ArgumentTypeError(f"{text!r}: give a whole number of megabytes (0: no limit)")
    return int(text)
