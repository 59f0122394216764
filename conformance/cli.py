"""``imc-conformance``: run a suite's corpus against an implementation, list it, re-render reports, rebuild it,
judge captures and live traffic. Building the parser imports nothing heavy; each command (``commands/``) imports
what it needs when it runs."""

from __future__ import annotations

import argparse
import sys

from .errors import CorpusError, UsageError
from .escaping import printable


class _Version(argparse.Action):
    """``--version``: the package's one version (pyproject.toml reads it from ``imc_conformance.__version__``)."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, default=argparse.SUPPRESS, help=None):
        super().__init__(option_strings, dest, nargs=0, default=default, help=help)

    def __call__(self, parser, namespace, values, option_string=None):
        from . import __version__

        print(f"imc-conformance {__version__}")
        parser.exit()


def build_parser(argv: list[str] | None = None) -> argparse.ArgumentParser:
    """The parser; given the command line ``argv``, only the command it names is registered (the rest are for
    --help and mistakes)."""
    parser = argparse.ArgumentParser(
        prog="imc-conformance",
        description="Conformance suite for underwater vehicle networking messages: IMC (LSTS) and ros_acomms_msgs "
                    "(WHOI). Start with: imc-conformance run --adapter imcpy",
        epilog="Exit codes: 0 every message passes, 1 a failure (FAIL, CRASH, TIMEOUT, WAIVER_STALE; NON_STRICT and INCONCLUSIVE with "
               "--strict), 2 a usage, corpus or adapter error, 130 interrupted.")
    parser.add_argument("--version", action=_Version, help="show the version and exit")
    sub = parser.add_subparsers(dest="command", required=True)
    wanted = next((a for a in argv or () if not a.startswith("-")), None)
    if wanted is None and argv and argv[0] == "--version":  # answered while parsing: no command is needed
        return parser
    from . import commands

    if wanted is not None and wanted not in commands.COMMANDS and wanted not in commands.suite_commands():
        wanted = None
    commands.add(sub, wanted)
    return parser


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    args = build_parser(argv).parse_args(argv)
    args.command_line = ["imc-conformance", *argv]  # what results record of how they were made
    from .core.waivers import WaiverError  # after parsing: --version and --help need none of the core

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
