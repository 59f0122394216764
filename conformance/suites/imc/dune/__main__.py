"""``python -m imc_conformance.suites.imc.dune build | conformance [...] | record [...] | relay [...] | restart --run DIR``."""

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
    if command == "record":
        from .conformance import record
        return record(rest)
    if command == "relay":
        from .relay import main as relay
        return relay(rest)
    if command == "restart":
        from .conformance import restart_world
        return restart_world(rest)
    print("usage: python -m imc_conformance.suites.imc.dune build | conformance [--reports DIR] [--no-robustness] | "
          "record [--seconds 120] [--out FILE] | relay [--seconds 60] [--impair SPEC] | restart --run DIR", file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
