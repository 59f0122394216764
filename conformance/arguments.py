"""The types of the command line's values (argparse types) and the edition a command works in, in one place below
every command: a suite's own commands (``serve``, ``ros-msg-files``) use them too. The numeric bounds are those of
``limits``: what a command accepts is what the readers of its results accept back (a recording of a run reads back
with the settings it was made with)."""

from __future__ import annotations

import argparse
import ipaddress
import math

from .limits import FUZZ_COUNT_MAX, MEMORY_LIMIT_MAX, SHARDS_MAX, STARTUP_MAX, TIME_SCALE_MAX, TIMEOUT_MAX


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
timeout_seconds = bounded(TIMEOUT_MAX)
startup_seconds = bounded(STARTUP_MAX)
time_scale = bounded(TIME_SCALE_MAX, "factor")


def megabytes(text: str) -> int:
    if not text.isdigit() or int(text) > MEMORY_LIMIT_MAX:
        raise argparse.ArgumentTypeError(f"{text!r}: give a whole number of megabytes, at most {MEMORY_LIMIT_MAX} "
                                         "(0: no limit)")
    return int(text)


def count(text: str) -> int:
    if not text.isdigit():
        raise argparse.ArgumentTypeError(f"{text!r}: give a whole number")
    return int(text)


def fuzz_count(text: str) -> int:
    """A whole number of examples or mutations per message, at most ``FUZZ_COUNT_MAX``."""
    value = count(text)
    if value > FUZZ_COUNT_MAX:
        raise argparse.ArgumentTypeError(f"{text!r}: at most {FUZZ_COUNT_MAX:,} per message")
    return value


def system_id(text: str) -> int:
    """An IMC-style numeric id for --src/--dst of a live run."""
    try:
        value = int(text, 0)
    except ValueError:
        value = -1
    if not 0 <= value < 0xFFFF:
        raise argparse.ArgumentTypeError(f"{text!r}: an id is 0 to 0xFFFE (decimal or 0x hex)")
    return value


def address(text: str) -> str | int:
    """An IP address, or a system id (decimal or 0x hex), for --src/--dst/--host of a capture."""
    try:
        return ipaddress.ip_address(text).compressed
    except ValueError:
        pass
    try:
        value = int(text, 0)
    except ValueError:
        value = -1
    if not 0 <= value <= 0xFFFF:
        raise argparse.ArgumentTypeError(f"{text!r}: give an IP address or a system id (0 to 0xFFFF, decimal or 0x hex)")
    return value


def chosen_edition(suite, given: str | None) -> str:
    """The edition a command works in: the one given (a usage error if the suite has none such), else the suite's
    first."""
    from .errors import UsageError

    edition = given or suite.editions[0]
    if edition not in suite.editions:
        raise UsageError(f"unknown edition {edition!r} (editions: {', '.join(suite.editions)})")
    return edition


def known_groups(suite, wanted, known) -> None:
    """A usage error naming each of the ``wanted`` messages (``--message``) that is not among ``known``."""
    from .errors import UsageError

    unknown = set(wanted) - set(known)
    if unknown:
        raise UsageError(f"unknown {suite.group_label}(s): {', '.join(sorted(unknown))}")


def window(start: float | None, end: float | None) -> None:
    """A usage error where ``--end`` comes before ``--start`` (seconds into a capture or a log)."""
    from .errors import UsageError

    if start is not None and end is not None and end < start:
        raise UsageError(f"--end {end:g} is before --start {start:g}")


def shard(text: str) -> tuple[int, int]:
    """K/N: the Kth of N shards (1 <= K <= N, N >= 2)."""
    k, sep, n = text.partition("/")
    if not sep or not k.isdigit() or not n.isdigit() or not 2 <= int(n) <= SHARDS_MAX or not 1 <= int(k) <= int(n):
        raise argparse.ArgumentTypeError(f"{text!r}: give K/N, the Kth of N shards (e.g. 1/4)")
    return int(k), int(n)


def port(text: str) -> int:
    if not text.isdigit() or not 0 < int(text) < 65536:
        raise argparse.ArgumentTypeError(f"{text!r} is not a UDP port")
    return int(text)


def listen_port(text: str) -> int:
    """A UDP port to listen on, 0 meaning any free one."""
    if not text.isdigit() or int(text) > 65535:
        raise argparse.ArgumentTypeError(f"{text!r}: a port is 0 to 65535")
    return int(text)


def real(accept, complaint: str):
    """An argparse type: a number ``accept(value)`` takes (NaN never), else ``complaint`` about the text."""
    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            value = math.nan
        if math.isnan(value) or not accept(value):
            raise argparse.ArgumentTypeError(f"{text!r}: {complaint}")
        return value
    return parse


offset_seconds = real(lambda v: 0 <= v < math.inf, "give seconds from the capture's first record (0 or more)")
probability = real(lambda v: 0 <= v < 1, "give a share between 0 and 1")
