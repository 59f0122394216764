"""``imc-conformance generate``: rebuild (or check) a suite's generated files from its definitions."""

from __future__ import annotations

from .options import add_suite


def add(sub) -> None:
    gen = sub.add_parser("generate", help="rebuild a suite's case files and coverage table from its definitions")
    add_suite(gen)
    gen.add_argument("--check", action="store_true", help="only report drift; exit 1 if any")
    gen.set_defaults(func=command)


def command(args) -> int:
    from ..suites import load_suite

    return load_suite(args.suite).generate(check=args.check)
