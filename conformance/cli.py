"""``imc-conformance``: run the corpus against an implementation, list it, re-render reports, rebuild it."""

from __future__ import annotations

import argparse
import datetime as dt
import importlib
import importlib.metadata
import importlib.util
import inspect
import json
import math
import shlex
import sys
from pathlib import Path

from .corpus_data import CorpusError, load_cases, select_cases
from .definitions import load_definitions
from .evaluate import expectation
from .render.common import printable
from .results import RunResult, failing
from .session import AdapterStartError

LIBRARY_ADAPTERS = {
    "imcpy": "imc_conformance.adapters.imcpy_adapter:adapter",
    "pyimclsts": "imc_conformance.adapters.pyimclsts_adapter:adapter",
}
SHIMS = {"imcpy-shim": "imcpy_shim.py", "pyimclsts-shim": "pyimclsts_shim.py"}
EDITIONS = ("imc-5.4.30", "imc-5.4.11")
REPORTS = ("json", "junit", "markdown", "html")


class UsageError(Exception):
    pass


def load_library_adapter(spec: str):
    """An adapter object from a built-in name, ``module:attribute`` or ``path/to/file.py:attribute``."""
    spec = LIBRARY_ADAPTERS.get(spec, spec)
    target, _, attr = spec.rpartition(":")
    if not target or not attr:
        raise UsageError(f"adapter {spec!r}: expected {', '.join([*LIBRARY_ADAPTERS, *SHIMS])}, module:attribute "
                         "or file.py:attribute (or --adapter-cmd for a subprocess)")
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
        return target_
    if not callable(target_):
        raise UsageError(f"adapter {spec!r} is a {type(target_).__name__}: expected an adapter object, "
                         "a class or a factory")
    try:  # a class or a zero-argument factory
        return target_()
    except Exception as exc:
        raise UsageError(f"cannot create the adapter {spec!r}: {type(exc).__name__}: {exc}") from exc


def adapter_choice(args) -> tuple[str, list[str] | None]:
    """The adapter's name and, for a subprocess adapter, its argv; usage errors for an ambiguous choice."""
    if args.adapter_cmd is None:
        return args.adapter or "imcpy", shim_argv(args.adapter) if args.adapter in SHIMS else None
    if args.adapter is not None:
        raise UsageError("give either --adapter or --adapter-cmd, not both")
    try:
        argv = shlex.split(args.adapter_cmd)
    except ValueError as exc:
        raise UsageError(f"--adapter-cmd cannot be split: {exc}") from exc
    if not argv:
        raise UsageError("--adapter-cmd is empty (an unset variable?): give the adapter program to run")
    return args.adapter_cmd, argv


def open_session(name: str, argv: list[str] | None, timeout: float):
    """The session for the chosen adapter: a subprocess when there is an argv, else a library adapter."""
    from .library import LibrarySession

    if argv is not None:
        from .subprocess_session import SubprocessSession

        return SubprocessSession(argv, name=name, timeout=timeout,
                                 hello_timeout=max(30.0, timeout))  # start-up (a JVM, class generation) takes longer
    return LibrarySession(load_library_adapter(name), name)


def shim_argv(name: str) -> list[str]:
    shim = Path(__file__).resolve().parent.parent / "adapters" / SHIMS[name]
    if not shim.exists():  # installed package: adapters/ is imc_conformance/adapters
        shim = Path(importlib.import_module("imc_conformance.adapters").__file__).parent / SHIMS[name]
    argv = [sys.executable, str(shim)]
    if name == "pyimclsts-shim":
        from .cache import cache_dir
        from .imc_xml import fetch_imc_xml
        argv += ["--imc-xml", str(fetch_imc_xml()), "--cache", str(cache_dir() / "pyimclsts-shim")]
    return argv


def select(cases: list[dict], args) -> list[dict]:
    unknown = set(args.message) - set(load_definitions().by_abbrev)
    if unknown:
        raise UsageError(f"unknown message(s): {', '.join(sorted(unknown))}")
    return select_cases(cases, args.edition, args.message, args.id, args.tag)


def command_list(args) -> int:
    for case in select(load_cases(args.vectors), args):
        print(f"{case['id']}\t{expectation(case, args.edition)}\t{case['clause']}")
    return 0


def command_run(args) -> int:
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TimeElapsedColumn

    from .render.terminal import print_result
    from .runner import run_cases
    from .waivers import WaiverError, load_waivers

    name, argv = adapter_choice(args)
    targets = report_targets(args)
    defs = load_definitions()
    everything = load_cases(args.vectors)
    cases = select(everything, args)
    if not cases:
        raise UsageError("the selection matches no case")
    waivers, notes = {}, []
    if args.waivers:
        try:
            waivers, notes = load_waivers(Path(args.waivers), {c["id"] for c in everything}, dt.date.today())
        except WaiverError as exc:
            raise UsageError(str(exc)) from exc
    console = terminal()
    session = open_session(name, argv, args.timeout)
    try:
        with Progress("[progress.description]{task.description}", BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                      console=Console(stderr=True), transient=True, disable=args.no_progress) as bar:
            task = bar.add_task("running", total=None)
            result = run_cases(session, cases, defs=defs, edition=args.edition, adapter=name, waivers=waivers,
                               strict=args.strict, notes=notes, progress=lambda n: bar.update(task, completed=n))
    except AdapterStartError as exc:
        raise UsageError(str(exc)) from exc
    finally:
        session.close()
    print_result(result, console)
    problems = write_reports(result, targets, console)
    if args.write_waivers:
        from .waivers import waivers_document
        failing_ids = [c.id for c in result.cases if failing(c.verdict, strict=False)]
        reason = f"failing on {dt.date.today().isoformat()} with {result.implementation}"
        problems += write_file(Path(args.write_waivers), json.dumps(waivers_document(failing_ids, reason), indent=1) + "\n",
                               f"waivers file ({len(failing_ids)} waivers)", console)
    if not result.complete:
        print("imc-conformance: interrupted; the reports hold the cases done so far", file=sys.stderr)
        return result.exit_code()
    return 2 if problems else result.exit_code()


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


def write_reports(result: RunResult, targets: dict[str, Path], console) -> int:
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
    from .render.terminal import print_result

    targets = report_targets(args)
    try:
        result = RunResult.from_dict(json.loads(Path(args.result).read_text(encoding="utf-8")))
    except (OSError, ValueError) as exc:  # JSONDecodeError and UnicodeDecodeError are ValueErrors
        raise UsageError(f"cannot read result {args.result}: {exc}") from exc
    console = terminal()
    print_result(result, console)
    return 2 if write_reports(result, targets, console) else result.exit_code()


def terminal():
    """A rich console; CI logs (not a terminal) get a wide table instead of rich's 80 columns."""
    from rich.console import Console

    return Console(highlight=False, width=None if sys.stdout.isatty() else 160)


def positive_seconds(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of seconds") from None
    if not math.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"{text!r}: give a positive, finite number of seconds")
    return value


def add_selection(parser) -> None:
    parser.add_argument("--edition", default=EDITIONS[0], choices=EDITIONS,
                        help="imc-5.4.30: what imcpy and deployed DUNE speak (default); imc-5.4.11: the seeds as written")
    parser.add_argument("--message", action="append", default=[], metavar="ABBREV", help="only this message (repeatable)")
    parser.add_argument("--id", action="append", default=[], metavar="GLOB", help="only case ids matching (repeatable)")
    parser.add_argument("--tag", action="append", default=[], help="only cases with this tag (repeatable), e.g. invalid")
    parser.add_argument("--vectors", type=Path, metavar="DIR", help="vector files to use instead of the packaged corpus")


def add_reports(parser) -> None:
    for fmt in REPORTS:
        parser.add_argument(f"--{fmt}", metavar="FILE", help=f"write the {fmt} report to FILE")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="imc-conformance",
        description="Conformance suite for IMC networking and acoustic messages. "
                    "Start with: imc-conformance run --adapter imcpy",
        epilog="Exit codes: 0 every message passes, 1 a failure (FAIL, CRASH, TIMEOUT, WAIVER_STALE; NON_STRICT with "
               "--strict), 2 a usage or adapter error.")
    parser.add_argument("--version", action="version",
                        version=f"imc-conformance {importlib.metadata.version('imc-conformance')}")
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run", help="run the corpus against an implementation")
    run.add_argument("--adapter", help="library adapter: imcpy (the default), pyimclsts, module:attribute or "
                                       "file.py:attribute (an object, a class or a factory); subprocess shims: "
                                       "imcpy-shim, pyimclsts-shim")
    run.add_argument("--adapter-cmd", metavar="CMD", help="a subprocess adapter speaking JSON lines (adapters/README.md); "
                                                          "split like a shell would, but never run by one")
    run.add_argument("--timeout", type=positive_seconds, default=5.0,
                     help="seconds per request for subprocess adapters (default 5)")
    add_selection(run)
    run.add_argument("--strict", action="store_true", help="NON_STRICT verdicts fail too")
    run.add_argument("--waivers", metavar="FILE", help="JSON waivers: case ids with a reason and optional expiry")
    run.add_argument("--write-waivers", metavar="FILE", help="write today's failures as a starting waivers file")
    run.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_reports(run)
    run.set_defaults(func=command_run)
    lst = sub.add_parser("list", help="list the selected cases (id, expectation, clause)")
    add_selection(lst)
    lst.set_defaults(func=command_list)
    rep = sub.add_parser("report", help="re-render a saved JSON result")
    rep.add_argument("result", help="a file written by run --json")
    add_reports(rep)
    rep.set_defaults(func=command_report)
    gen = sub.add_parser("generate", help="rebuild vectors/imc/cases and the coverage table from the definitions")
    gen.add_argument("--check", action="store_true", help="only report drift; exit 1 if any")
    gen.set_defaults(func=lambda a: importlib.import_module("imc_conformance.corpus.build").main(["--check"] if a.check else []))
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except (UsageError, CorpusError) as exc:
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
