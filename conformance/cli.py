"""``imc-conformance``: run a suite's corpus against an implementation, list it, re-render reports, rebuild it."""

from __future__ import annotations

import argparse
import datetime as dt
import importlib
import importlib.metadata
import importlib.util
import inspect
import json
import shlex
import sys
from pathlib import Path

from .arguments import megabytes, positive_seconds, startup_seconds, time_scale
from .core.cases import expectation, select_cases
from .core.session import AdapterStartError
from .core.verdicts import failing
from .core.waivers import WaiverError
from .files import CorpusError
from .render.common import printable
from .live import system_id
from .suites import names as suite_names
from .usage import UsageError

REPORTS = ("json", "junit", "markdown", "html")
DEFAULT_MEMORY_MB = 2048


def load_library_adapter(spec: str, suite, arguments: dict[str, str] | None = None):
    """An adapter object from a built-in name, ``module:attribute`` or ``path/to/file.py:attribute`` (an
    adapter object, a class or a factory; ``arguments`` are passed to the class or factory)."""
    builtin = suite.adapters.get(spec)
    target, _, attr = (builtin.library if builtin else spec).rpartition(":")
    if not target or not attr:
        raise UsageError(f"adapter {spec!r}: expected {', '.join(suite.adapters)}, module:attribute or "
                         "file.py:attribute (or --adapter-cmd for a subprocess)")
    try:
        if target.endswith(".py"):
            if not Path(target).is_file():
                raise UsageError(f"adapter file {target} does not exist")
            spec_ = importlib.util.spec_from_file_location(Path(target).stem, target)
            module = importlib.util.module_from_spec(spec_)
            spec_.loader.exec_module(module)
        else:
            module = importlib.import_module(target)
        target_ = getattr(module, attr)
    except UsageError:
        raise
    except Exception as exc:
        raise UsageError(f"cannot load adapter {spec!r}: {type(exc).__name__}: {exc}") from exc
    if hasattr(target_, "decode") and not inspect.isclass(target_):
        if arguments:
            raise UsageError(f"adapter {spec!r} is an object: it takes no --adapter-arg")
        return target_
    if not callable(target_):
        raise UsageError(f"adapter {spec!r} is a {type(target_).__name__}: expected an adapter object, "
                         "a class or a factory")
    try:  # a class or a factory
        return target_(**(arguments or {}))
    except Exception as exc:
        raise UsageError(f"cannot create the adapter {spec!r}: {type(exc).__name__}: {exc}") from exc


def adapter_choice(args, suite) -> tuple[str, list[str] | None]:
    """The adapter's name and, for a subprocess adapter, its argv; usage errors for an ambiguous choice."""
    if args.adapter_cmd is None:
        name = args.adapter or next(iter(suite.adapters))
        builtin = suite.adapters.get(name)
        return name, builtin.argv() if builtin is not None and builtin.argv is not None else None
    if args.adapter is not None:
        raise UsageError("give either --adapter or --adapter-cmd, not both")
    try:
        argv = shlex.split(args.adapter_cmd)
    except ValueError as exc:
        raise UsageError(f"--adapter-cmd cannot be split: {exc}") from exc
    if not argv:
        raise UsageError("--adapter-cmd is empty (an unset variable?): give the adapter program to run")
    return args.adapter_cmd, argv


def adapter_arguments(args) -> dict[str, str]:
    out = {}
    for item in args.adapter_arg:
        name, sep, value = item.partition("=")
        if not sep or not name.isidentifier():
            raise UsageError(f"--adapter-arg {item!r}: expected NAME=VALUE")
        out[name] = value
    return out


def open_session(name: str, argv: list[str] | None, args, suite):
    """The session for the chosen adapter: a subprocess when there is an argv, else a library adapter; either
    also runs the scenarios of a handler it calls (sessions/calls.py)."""
    from .sessions.calls import CallTarget
    from .sessions.library import LibrarySession

    if argv is not None:
        from .sessions.subprocess import SubprocessSession

        if args.adapter_arg:
            raise UsageError("--adapter-arg is for library adapters; a subprocess adapter takes its own arguments")
        return CallTarget(SubprocessSession(argv, name=name, encoding_param=suite.encoding_param, timeout=args.timeout,
                                            hello_timeout=max(30.0, args.timeout),  # start-up (a JVM, class generation) takes longer
                                            memory_limit=args.memory_limit * 1024 * 1024))
    return CallTarget(LibrarySession(load_library_adapter(name, suite, adapter_arguments(args)), name))


def selection(args):
    """The suite, every case of its corpus, and the cases the options select."""
    from .files import open_corpus

    suite, everything = open_corpus(args.suite, args.vectors)
    args.edition = args.edition or suite.editions[0]
    if args.edition not in suite.editions:
        raise UsageError(f"unknown edition {args.edition!r} of the suite {suite.name!r} "
                         f"(editions: {', '.join(suite.editions)})")
    unknown = set(args.message) - {g.name for g in suite.groups}
    if unknown:
        raise UsageError(f"unknown {suite.group_label}(s): {', '.join(sorted(unknown))}")
    return suite, everything, select_cases(everything, args.edition, args.message, args.id, args.tag)


def command_list(args) -> int:
    suite, _, cases = selection(args)
    if args.scenarios:
        from .live import list_live_cases
        try:
            return list_live_cases(suite, cases)
        except ValueError as exc:
            raise UsageError(str(exc)) from exc
    for case in cases:
        print(f"{case.id}\t{expectation(case.data, args.edition)}\t{case.data['clause']}")
    return 0


def command_run(args) -> int:
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TimeElapsedColumn

    from . import live
    from .core.runner import run_cases
    from .files import load_waivers
    from .render.terminal import print_result

    targets = report_targets(args)
    suite, everything, cases = selection(args)
    try:
        options = live.options(args, suite, everything)
    except ValueError as exc:
        raise UsageError(str(exc)) from exc
    if args.target and (args.adapter or args.adapter_cmd):
        raise UsageError("give either --target (a live node) or --adapter/--adapter-cmd, not both")
    name, argv = (args.target, None) if args.target else adapter_choice(args, suite)
    if not cases:
        raise UsageError("the selection matches no case")
    if args.dry_run:
        if args.pcap:
            raise UsageError("--pcap records what a run sends and receives; --dry-run sends nothing")
        return live.dry_run(suite, cases, args, options)
    waivers, notes = {}, []
    if args.waivers:
        try:
            waivers, notes = load_waivers(Path(args.waivers), {c.id for c in everything}, dt.date.today())
        except WaiverError as exc:
            raise UsageError(str(exc)) from exc
    console = terminal()
    args.first_unique = live.first_unique() if args.target else None
    recorder = open_recording(args, suite, cases, options)
    try:
        session = live.open_target(args, suite, recorder) if args.target else open_session(name, argv, args, suite)
    except ValueError as exc:
        if recorder is not None:
            recorder.close(complete=False)
        raise UsageError(str(exc)) from exc
    result = None
    try:
        with Progress("[progress.description]{task.description}", BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                      console=Console(stderr=True, emoji=False), transient=True, disable=args.no_progress) as bar:
            task = bar.add_task("running", total=None)
            result = run_cases(session, suite, cases, edition=args.edition, adapter=name, errata=args.errata,
                               waivers=waivers, strict=args.strict, notes=notes + live.notes(args, options),
                               progress=lambda n: bar.update(task, completed=n), options=options)
    except AdapterStartError as exc:
        raise UsageError(str(exc)) from exc
    finally:
        session.close()
        if recorder is not None:
            recorder.close(complete=result is not None and result.complete)
    print_result(result, console)
    problems = write_reports(result, targets, console)
    if recorder is not None and recorder.failed:
        print(f"imc-conformance: cannot write the pcapng to {printable(str(args.pcap))}: {recorder.failed} (the run "
              "and its other reports went on)", file=sys.stderr)
        problems += 1
    elif recorder is not None:
        console.print(f"pcapng of the exchange ({recorder.count} datagrams): {printable(str(args.pcap))}",
                      highlight=False, markup=False)
    if args.write_waivers:
        from .core.waivers import waivers_document
        failing_ids = [c.id for c in result.cases if failing(c.verdict, strict=False)]
        reason = f"failing on {dt.date.today().isoformat()} with {result.implementation}"
        problems += write_file(Path(args.write_waivers), json.dumps(waivers_document(failing_ids, reason), indent=1) + "\n",
                               f"waivers file ({len(failing_ids)} waivers)", console)
    if not result.complete:
        print("imc-conformance: interrupted; the reports hold the cases done so far", file=sys.stderr)
        return result.exit_code()
    return 2 if problems else result.exit_code()


def open_recording(args, suite, cases, options):
    """The recorder of ``--pcap`` (a live run's datagrams as pcapng), or None."""
    if not args.pcap:
        return None
    if not args.target:
        raise UsageError("--pcap records a live run's datagrams: give --target udp://HOST:PORT")
    from .capture.recording import Recorder, about_run

    ids = [c.id for c in cases if c.kind == "scenario"]
    about = about_run(suite.name, args.edition, ids, options, args.target, args.src, args.dst, args.startup,
                      args.first_unique)
    try:
        Path(args.pcap).parent.mkdir(parents=True, exist_ok=True)
        return Recorder(Path(args.pcap), about)
    except OSError as exc:
        raise UsageError(f"cannot write the pcapng to {args.pcap}: {exc.strerror or exc}") from exc


def report_targets(args) -> dict[str, Path]:
    """The requested reports by format; two formats to one file is a usage error."""
    targets = {fmt: Path(getattr(args, fmt)) for fmt in REPORTS if getattr(args, fmt)}
    seen: dict[Path, str] = {}
    for fmt, path in targets.items():
        key = path.resolve()
        if key in seen:
            raise UsageError(f"--{seen[key]} and --{fmt} write to the same file {path}")
        seen[key] = fmt
    return targets


def write_reports(result, targets: dict[str, Path], console) -> int:
    """Write each requested report and say where; a report that cannot be written is reported and skipped.
    Returns the number of reports that could not be written."""
    if not targets:
        return 0
    from .render import RENDERERS

    return sum(write_file(path, RENDERERS[fmt](result), f"{fmt} report", console) for fmt, path in targets.items())


def write_file(path: Path, text: str, what: str, console) -> int:
    """Write ``text`` to ``path`` (creating its folder) and say so; 1 after a one-line error if that fails."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
    except OSError as exc:
        print(f"imc-conformance: cannot write the {what} to {printable(str(path))}: {exc.strerror or exc}",
              file=sys.stderr)
        return 1
    console.print(f"{what}: {printable(str(path))}", highlight=False, markup=False)
    return 0


def command_report(args) -> int:
    from .files import read_result
    from .render.terminal import print_result

    targets = report_targets(args)
    try:
        result = read_result(Path(args.result))
    except ValueError as exc:  # not JSON, unreadable, or not a valid result
        raise UsageError(f"cannot read the result {exc}") from exc
    console = terminal()
    print_result(result, console)
    return 2 if write_reports(result, targets, console) else result.exit_code()


def command_generate(args) -> int:
    from .suites import load_suite

    return load_suite(args.suite).generate(check=args.check)


def terminal():
    """A rich console that interprets nothing it is given (no emoji codes, no highlighting; markup is escaped by
    the renderer); CI logs (not a terminal) get a wide table instead of rich's 80 columns."""
    from rich.console import Console

    return Console(highlight=False, emoji=False, width=None if sys.stdout.isatty() else 160)


def add_suite(parser) -> None:
    parser.add_argument("--suite", default=suite_names()[0], choices=suite_names(),
                        help="imc (default): IMC messages 150-216; ros_acomms: ros_acomms_msgs types")


def add_selection(parser) -> None:
    add_suite(parser)
    parser.add_argument("--edition", help="the edition to judge against (default: the suite's first); imc: imc-5.4.30 "
                                          "(what imcpy and deployed DUNE speak) or imc-5.4.11 (the seeds as written)")
    parser.add_argument("--message", action="append", default=[], metavar="NAME",
                        help="only this message or type (repeatable)")
    parser.add_argument("--id", action="append", default=[], metavar="GLOB", help="only case ids matching (repeatable)")
    parser.add_argument("--tag", action="append", default=[], help="only cases with this tag (repeatable), e.g. invalid")
    parser.add_argument("--vectors", type=Path, metavar="DIR",
                        help="a suite folder (like vectors/imc) or folder of case files to use instead of the packaged corpus")


def add_reports(parser) -> None:
    for fmt in REPORTS:
        parser.add_argument(f"--{fmt}", metavar="FILE", help=f"write the {fmt} report to FILE")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="imc-conformance",
        description="Conformance suite for underwater vehicle networking messages: IMC (LSTS) and ros_acomms_msgs "
                    "(WHOI). Start with: imc-conformance run --adapter imcpy",
        epilog="Exit codes: 0 every message passes, 1 a failure (FAIL, CRASH, TIMEOUT, WAIVER_STALE; NON_STRICT and INCONCLUSIVE with "
               "--strict), 2 a usage, corpus or adapter error, 130 interrupted.")
    parser.add_argument("--version", action="version",
                        version=f"imc-conformance {importlib.metadata.version('imc-conformance')}")
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run", help="run a suite's corpus against an implementation")
    run.add_argument("--adapter", help="a built-in adapter of the suite (imc: imcpy, the default, pyimclsts, imcpy-shim, "
                                       "pyimclsts-shim; ros_acomms: rosbags, the default, genpy), or a library adapter "
                                       "as module:attribute or file.py:attribute (an object, a class or a factory)")
    run.add_argument("--adapter-arg", action="append", default=[], metavar="NAME=VALUE",
                     help="an argument for a library adapter's class or factory (repeatable)")
    run.add_argument("--adapter-cmd", metavar="CMD", help="a subprocess adapter speaking JSON lines (adapters/README.md); "
                                                          "split like a shell would, but never run by one")
    run.add_argument("--timeout", type=positive_seconds, default=5.0,
                     help="seconds per request for subprocess adapters (default 5)")
    run.add_argument("--memory-limit", type=megabytes, default=DEFAULT_MEMORY_MB, metavar="MB",
                     help=f"data memory a subprocess adapter may use (default {DEFAULT_MEMORY_MB}; 0: no limit): one "
                          "that tries to allocate what a hostile length asks for fails instead of the machine")
    add_selection(run)
    run.add_argument("--errata", metavar="KEY", help="the implementation errata that explain failures "
                                                     "(default: the key the adapter's hello declares)")
    run.add_argument("--strict", action="store_true", help="NON_STRICT verdicts fail too")
    run.add_argument("--waivers", metavar="FILE", help="JSON waivers: case ids with a reason and optional expiry")
    run.add_argument("--write-waivers", metavar="FILE", help="write today's failures as a starting waivers file")
    run.add_argument("--no-progress", action="store_true", help="no progress bar")
    live_group = run.add_argument_group("scenarios and live targets")
    live_group.add_argument("--target", metavar="URL", help="a live node to run the scenarios against: udp://HOST:PORT or "
                                                      "imc+udp://HOST:PORT/ (IPv6 as udp://[::1]:PORT)")
    live_group.add_argument("--bind", metavar="HOST[:PORT]", help="where the session listens (default: loopback, any port)")
    live_group.add_argument("--src", type=system_id, default=None, metavar="ID",
                      help="the session's own IMC id (default 0x4CF0)")
    live_group.add_argument("--dst", type=system_id, default=None, metavar="ID",
                      help="the node's IMC id: start at once instead of waiting for a frame from the node")
    live_group.add_argument("--startup", type=startup_seconds, default=10.0, metavar="SECONDS",
                      help="how long to wait for a first valid frame from the target (default 10)")
    live_group.add_argument("--allow-multicast", action="store_true",
                      help="allow a multicast or broadcast target or bind (never needed on loopback)")
    live_group.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                      help="what a scenario needs from the target, e.g. peer=lauv-xplore-2 (list --scenarios names them)")
    live_group.add_argument("--allow-effects", nargs="?", const="all", metavar="EFFECTS",
                      help="run scenarios with side effects on the target: all, or a comma-separated list "
                           "(default: only effect-free scenarios)")
    live_group.add_argument("--claims", metavar="FILE", help='JSON {"services": [...]}: the services the target implements; '
                                                       "scenarios of other services are UNSUPPORTED")
    live_group.add_argument("--profile", metavar="NAME", help="where deployed practice differs from the seeds (default seed)")
    live_group.add_argument("--time-scale", type=time_scale, default=1.0, metavar="F",
                      help="multiply every time bound by F (slow links)")
    live_group.add_argument("--pcap", metavar="FILE", help="write every datagram of the run as pcapng, each commented "
                                                           "with its scenario and step (imc-conformance pcap replays it)")
    live_group.add_argument("--dry-run", action="store_true", help="print what the scenarios would send, and send nothing")
    live_group.add_argument("--robustness", action="store_true",
                            help="also run the robustness phase: every corpus frame, then 10,000 garbage datagrams, "
                                 "after which every request kind answered before must still be answered")
    live_group.add_argument("--replay-effects", action="store_true",
                            help="with --robustness: also replay the corpus's accepted frames of messages with effects "
                                 "(their destinations are the corpus's own: never against a real vehicle)")
    live_group.add_argument("--restart-cmd", metavar="CMD",
                            help="a command that restarts the target (split like a shell would, never run by one): "
                                 "lets the robustness phase bisect to the frame that silenced it")
    add_reports(run)
    run.set_defaults(func=command_run)
    lst = sub.add_parser("list", help="list the selected cases (id, expectation, clause)")
    add_selection(lst)
    lst.add_argument("--scenarios", action="store_true",
                     help="only scenarios, with what they need (--param), their effects and service")
    lst.set_defaults(func=command_list)
    rep = sub.add_parser("report", help="re-render a saved JSON result")
    rep.add_argument("result", help="a file written by run --json")
    add_reports(rep)
    rep.set_defaults(func=command_report)
    gen = sub.add_parser("generate", help="rebuild a suite's case files and coverage table from its definitions")
    add_suite(gen)
    gen.add_argument("--check", action="store_true", help="only report drift; exit 1 if any")
    gen.set_defaults(func=command_generate)
    from . import capture_command, watch_command
    from .suites import load_suite

    capture_command.add_command(sub, add_suite, add_reports, positive_seconds)
    watch_command.add_command(sub, add_suite, add_reports, positive_seconds, capture_command.address,
                              capture_command.add_judging)
    for name in suite_names():
        load_suite(name).commands(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except (UsageError, CorpusError, WaiverError) as exc:
        print(f"imc-conformance: {printable(str(exc))}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:  # before any case ran (loading, starting the adapter): nothing to report
        print("imc-conformance: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # output piped into head(1) and the like
        sys.stderr.close()
        return 0


if __name__ == "__main__":
    sys.exit(main())
