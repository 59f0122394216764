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
    logs = [_Log(Path(p)) for p in args.files]  # each opened, its format recognised, and closed again
    try:
        suite, reader, notes, damage = _reader(args, logs)
        selection = Selection(None, frozenset(args.message), args.src, args.dst, args.host, args.start, args.end,
                              args.list_frames, args.time_scale)
        judge = CaptureJudge(suite.name, reader.rules, reader.edition, selection, log=True)
        started = dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds")
        began, complete = time.perf_counter(), True
        try:
            for log in logs:  # one open at a time: memory and open files flat in the number of logs
                _judge(judge, reader, log, damage, len(logs) > 1)
        except KeyboardInterrupt:
            complete = False
    finally:
        for log in logs:
            log.close()
    result = judge.result(implementation=", ".join(log.path.name or str(log.path) for log in logs), started=started,
                          duration=round(time.perf_counter() - began, 3), strict=args.strict, title=suite.title,
                          notes=notes + reader.notes + damage, complete=complete)
    result.provenance = provenance(args, suite, {key: getattr(args, key) for key in (
        "message", "src", "dst", "host", "start", "end")})
    return finish(result, targets, damage, complete)


class _Log:
    """A log named on the command line: opened once to recognise its format by its first decompressed bytes
    (``head``) and closed again, then opened again to be judged (``open``), so that only one is open at a time.
    Standard input, which cannot be read twice, keeps its stream open between the two."""

    def __init__(self, path: Path):
        from ..capture.logs import HEAD

        self.path, self.kept = path, None
        stream, first, pieces = _opened(path)
        self.head = first[:HEAD]
        if str(path) == "-":
            self.kept = stream, _again(first, pieces)
        else:
            stream.handle.close()

    def open(self):
        """(its stream, its decompressed pieces); ValueError with one line if it cannot be opened again."""
        from ..capture.streams import open_stream

        if self.kept is not None:
            kept, self.kept = self.kept, None
            return kept
        stream = open_stream(self.path)
        return stream, stream.pieces()

    def close(self) -> None:
        if self.kept is not None:
            self.kept[0].handle.close()


def _opened(path: Path):
    """(its stream, its first decompressed piece, the rest of its pieces); a usage error for a file that cannot be
    read or is empty."""
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
    return stream, first, pieces


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
    if explicit:
        suite = open_suite(args.suite or _default_suite(), args.vectors)
        reader = _log_reader(suite)
    else:
        suite, reader = _recognising(logs[0].head, logs[0].path)
    for log in logs:
        if not reader.recognises(log.head):
            raise UsageError(f"{log.path}: not a {reader.format} log (it starts {log.head[:8].hex()})")
    notes, damage, own = [], [], set()
    for log in logs:
        found, said, problems = reader.beside(log.path, not explicit)
        notes += [n for n in said if n not in notes]
        damage += problems
        own.add(found)
    if len(own) > 1:
        raise UsageError("the logs come with different definitions beside them: judge them one at a time")
    beside = own.pop()
    if args.edition is not None and beside is not None and args.edition not in beside.editions \
            and args.edition in suite.editions:
        raise UsageError(f"the definitions beside the log (edition {', '.join(beside.editions)}) have no edition "
                         f"{args.edition!r}: --suite {suite.name} judges it by the suite's own, which have")
    suite = beside or suite
    if args.edition is not None:
        chosen_edition(suite, args.edition)
    reader = _log_reader(suite, args.edition)
    if not reader.addressed and any(v is not None for v in (args.src, args.dst, args.host)):
        raise UsageError(f"--src, --dst and --host do not apply to a {reader.format}: its messages name no system "
                         "(--message and --start/--end do)")
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


def _judge(judge, reader, log: _Log, damage: list[str], named: bool) -> None:
    """Feed every frame of one log to the judge, and what the log says of its frames; close it."""
    from ..capture.logs import Logged

    try:
        stream, pieces = log.open()
    except ValueError as exc:  # gone or changed since its format was recognised
        damage.append(str(exc))
        return
    stream.gaps = reader.gaps
    source, path = f"{log.path.name} " if named else "", log.path
    logged, found = judge.logged, judge.found
    try:
        for unit in reader.units(pieces, stream.damage, str(path)):  # the stream's lines and the reader's, in order
            if unit.__class__ is Logged:
                logged(unit, source)
            else:
                found(unit, source)
    finally:
        stream.handle.close()
    damage += stream.damage
