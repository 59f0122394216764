"""``imc-conformance log``: judge mission logs frame by frame and exchange by exchange, as captures are judged. Each
suite reads its own format (``Suite.log_reader``: IMC's LSF, plain or compressed; ros_acomms' ROS 1 bags); without
``--suite`` or ``--vectors`` the format of the first file chooses the suite, and a log that brings its own
definitions (files beside it: ``LogReader.beside``) is judged by them."""

from __future__ import annotations

import argparse
import datetime as dt
import time
from pathlib import Path

from ..errors import UsageError
from ..arguments import address, known_groups, offset_seconds, window
from .options import add_judging, add_reports


def system(text: str) -> int:
    """A system id for --src/--dst/--host of a log (it holds no IP addresses)."""
    value = address(text)
    if isinstance(value, str):
        raise argparse.ArgumentTypeError(f"{text!r}: a log holds no IP addresses: give a system id (0 to 0xFFFF)")
    return value


def add(sub) -> None:
    log = sub.add_parser("log", help="judge mission logs (IMC: LSF, plain, gzip or bzip2; ros_acomms: ROS 1 bags): "
                                     "every frame, every exchange")
    log.add_argument("files", nargs="+", metavar="FILE", help="logs of one format (DUNE's Data.lsf[.gz|.bz2], a "
                                                               "ROS 1 .bag; - reads standard input)")
    add_judging(log, log=True)
    log.add_argument("--src", type=system, metavar="ID", help="only frames from this system id")
    log.add_argument("--dst", type=system, metavar="ID", help="only frames to this system id")
    log.add_argument("--host", type=system, metavar="ID", help="only frames from or to this system id (keeps whole "
                                                               "exchanges)")
    log.add_argument("--start", type=offset_seconds, metavar="SECONDS", help="only from this many seconds into the log")
    log.add_argument("--end", type=offset_seconds, metavar="SECONDS", help="only until this many seconds into the log")
    add_reports(log)
    log.set_defaults(func=command)


def command(args) -> int:
    from ..capture.judge import CaptureJudge, Selection
    from .output import finish, report_targets
    from .provenance import provenance

    targets = report_targets(args)
    window(args.start, args.end)
    logs = [_opened(Path(p)) for p in args.files]
    try:
        suite, reader, notes, damage = _reader(args, logs)
        selection = Selection(None, frozenset(args.message), args.src, args.dst, args.host, args.start, args.end,
                              args.list_frames, args.time_scale)
        judge = CaptureJudge(suite.name, reader.rules, reader.edition, selection, log=True)
        started = dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds")
        began, complete = time.perf_counter(), True
        try:
            for path, stream, _, pieces in logs:
                _judge(judge, reader, path, stream, pieces, damage, len(logs) > 1)
        except KeyboardInterrupt:
            complete = False
    finally:
        for _, stream, _, _ in logs:
            stream.handle.close()
    result = judge.result(implementation=", ".join(p.name or str(p) for p, _, _, _ in logs), started=started,
                          duration=round(time.perf_counter() - began, 3), strict=args.strict, title=suite.title,
                          notes=notes + reader.notes + damage, complete=complete)
    result.provenance = provenance(args, suite, {key: getattr(args, key) for key in (
        "message", "src", "dst", "host", "start", "end")})
    return finish(result, targets, damage, complete)


def _opened(path: Path):
    """(path, its stream, the first HEAD bytes of its decompressed content, its decompressed pieces); a usage error
    for a file that cannot be read or is empty."""
    from ..capture.logs import HEAD
    from ..capture.streams import open_stream

    try:
        stream = open_stream(path)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    pieces = stream.pieces()
    first = next(pieces, b"")
    if not first:
        stream.handle.close()
        raise UsageError("; ".join(stream.damage) or f"{path}: empty, not a log")
    return path, stream, first[:HEAD], _again(first, pieces)


def _again(first: bytes, rest):
    """The pieces of a stream whose first was read to recognise its format."""
    yield first
    yield from rest


def _reader(args, logs):
    """The suite and its log reader for these logs (the suite named, else the one reading the first log's format;
    then the definitions the logs bring, unless --suite or --vectors said which), with notes and problems."""
    from ..files import open_suite
    from ..arguments import chosen_edition

    explicit = args.suite is not None or args.vectors is not None
    heads = [head for _, _, head, _ in logs]
    if explicit:
        suite = open_suite(args.suite or _default_suite(), args.vectors)
        reader = _log_reader(suite)
    else:
        suite, reader = _recognising(heads[0], logs[0][0])
    for path, _, head, _ in logs:
        if not reader.recognises(head):
            raise UsageError(f"{path}: not a {reader.format} log (it starts {head[:8].hex()})")
    notes, damage, own = [], [], set()
    for path, _, _, _ in logs:
        found, said, problems = reader.beside(path, not explicit)
        notes += [n for n in said if n not in notes]
        damage += problems
        own.add(found)
    if len(own) > 1:
        raise UsageError("the logs come with different definitions beside them: judge them one at a time")
    suite = own.pop() or suite
    if args.edition is not None:
        chosen_edition(suite, args.edition)
    reader = _log_reader(suite, args.edition)
    known_groups(suite, args.message, reader.rules.keys)
    return suite, reader, notes, damage


def _default_suite() -> str:
    from ..suites import names

    return names()[0]


def _log_reader(suite, edition: str | None = None):
    try:
        return suite.log_reader(edition)
    except ValueError as exc:
        raise UsageError(str(exc)) from None


def _recognising(head: bytes, path: Path):
    """The suite whose log format the log starting with ``head`` is, and its reader; a usage error if none reads it."""
    from ..suites import load_suite, packages

    formats = []
    for name in packages():
        suite = load_suite(name)
        try:
            reader = suite.log_reader()
        except ValueError:
            continue
        if reader.recognises(head):
            return suite, reader
        formats.append(reader.format)
    raise UsageError(f"{path}: not a log of a format the suites read ({', '.join(formats)}): it starts "
                     f"{head[:8].hex()}")


def _judge(judge, reader, path: Path, stream, pieces, damage: list[str], named: bool) -> None:
    """Feed every frame of one log to the judge, and what the log says of its frames."""
    from ..capture.logs import Logged

    source, said = f"{path.name} " if named else "", []
    logged, found = judge.logged, judge.found
    for unit in reader.units(pieces, said, str(path)):
        if unit.__class__ is Logged:
            logged(unit, source)
        else:
            found(unit, source)
    damage += stream.damage + said
