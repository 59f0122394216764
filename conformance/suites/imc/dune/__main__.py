"""``python -m imc_conformance.suites.imc.dune build | conformance [...] | restart --run DIR``."""

from __future__ import annotations

import sys


def main(argv: list[str]) -> int:
    command, rest = (argv[0], argv[1:]) if argv else ("", [])
    if command == "build":
        from .build import main as build
        return build()
    if command == "conformance":
        from .conformance import main as conformance
        return conformance(rest)
    if command == "restart":
        from .conformance import restart_world
        return restart_world(rest)
    print("usage: python -m imc_conformance.suites.imc.dune build | conformance [--reports DIR] [--no-robustness] | "
          "restart --run DIR", file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
