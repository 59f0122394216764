"""``python -m imc_conformance.benchmark``: every row measured in one run, then the targets."""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

from ..core.cases import expectation
from ..files import open_corpus
from . import __doc__ as DOC
from .fuzzing import fuzz_rows
from .inprocess import library_rows, ros_rows
from .live import live_rows
from .measure import COUNTS, EDITION, command_env, install_wheel
from .programs import subprocess_rows
from .recordings import capture_rows, log_rows
from .startup import startup_rows
from .targets import target_lines
from .whole import whole_rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m imc_conformance.benchmark", description=DOC.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--per-case-sample", type=int, default=40, help="cases run with one process each")
    parser.add_argument("--json", metavar="FILE", help="also write every median and target as JSON")
    for part in ("startup", "subprocess", "ros", "live", "robustness", "capture", "logs", "fuzz", "whole", "node-flood", "relay"):
        parser.add_argument(f"--skip-{part}", action="store_true")
    args = parser.parse_args(argv)

    suite, everything = open_corpus("imc")
    cases = [c for c in everything if c.kind == "vector" and expectation(c.data, EDITION) is not None]
    medians: dict[str, float] = {}
    installed = tempfile.TemporaryDirectory(prefix="imc-conformance-installed-")
    if not args.skip_startup:
        install_wheel(Path(installed.name))
        medians |= startup_rows(args.repeat)
    medians |= library_rows(suite, cases, args.repeat)
    if not args.skip_ros:
        medians |= ros_rows(args.repeat)
    if not args.skip_subprocess:
        medians |= subprocess_rows(suite, cases, args.repeat, args.per_case_sample)
    if not args.skip_live:
        medians |= live_rows(suite, everything, args.repeat, not args.skip_robustness)
    if not args.skip_capture:
        medians |= capture_rows(suite, min(args.repeat, 3))
    if not args.skip_logs:
        medians |= log_rows(min(args.repeat, 3))
    if not args.skip_fuzz:
        medians |= fuzz_rows(suite, everything)
    if not args.skip_whole:
        medians |= whole_rows(args.repeat)
    if not args.skip_node_flood:
        from ..suites.imc.node.flood import flood_rows
        medians |= flood_rows()
    if not args.skip_relay:
        from ..relay.flood import flood_rows as relay_flood_rows
        medians |= relay_flood_rows(command_env())
    installed.cleanup()
    lines = target_lines(medians)
    print("\n".join(lines))
    if args.json:
        Path(args.json).write_text(json.dumps({"medians": medians, "counts": COUNTS, "targets": lines}, indent=1) + "\n",
                                   encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
