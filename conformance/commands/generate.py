"""``imc-conformance generate``: rebuild (or check) a suite's generated files from its definitions."""

from __future__ import annotations

from pathlib import Path

from ..errors import UsageError
from .options import add_suite


def add(sub) -> None:
    gen = sub.add_parser("generate", help="rebuild a suite's case files and coverage table from its definitions")
    add_suite(gen)
    gen.add_argument("--check", action="store_true", help="only report drift; exit 1 if any")
    gen.add_argument("--from", dest="source", type=Path, metavar="FILE",
                     help="build a suite folder from this protocol description instead (imc: an IMC.xml), into --out")
    gen.add_argument("--out", type=Path, metavar="DIR", help="the folder --from writes (then: run --vectors DIR)")
    gen.set_defaults(func=command)


def command(args) -> int:
    from ..suites import load_suite

    suite = load_suite(args.suite)
    if args.source is None and args.out is None:
        return suite.generate(check=args.check)
    if args.source is None or args.out is None or args.check:
        raise UsageError("--from FILE and --out DIR go together (and without --check)")
    build = getattr(suite, "generate_from", None)
    if build is None:
        raise UsageError(f"the {suite.name} suite builds no folder from a protocol description")
    try:
        return build(args.source, args.out)
    except ValueError as exc:
        raise UsageError(f"{args.source}: {exc}" if not str(exc).startswith(str(args.source)) else str(exc)) from None
