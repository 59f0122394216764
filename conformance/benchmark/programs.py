"""Subprocess rows: the imcpy shim batched, one request a line and one process per case; the compiled programs."""

from __future__ import annotations

import subprocess
import sys

from ..core.cases import expectation
from ..core.runner import run_cases
from ..files import open_corpus
from .measure import COUNTS, EDITION, ROS_EDITION, median_of, timed


def through(argv: list[str], name: str, suite, cases, edition: str, **options) -> None:
    """One run of ``cases`` through a subprocess session of ``argv`` (``options``: the session's), closed after."""
    from ..sessions.subprocess import SubprocessSession

    session = SubprocessSession(argv, name=name, encoding_param=suite.encoding_param, **options)
    try:
        run_cases(session, suite, cases, edition=edition, adapter=name)
    finally:
        session.close()


def subprocess_rows(suite, cases, repeat: int, sample_size: int) -> dict[str, float]:
    shim = suite.adapters["imcpy-shim"].argv()
    out = {"subprocess": median_of(repeat, lambda: through(shim, "imcpy-shim", suite, cases, EDITION, batch=True)),
           "subprocess per line": median_of(repeat, lambda: through(shim, "imcpy-shim", suite, cases, EDITION,
                                                                    batch=False))}
    sample = cases[:: max(1, len(cases) // sample_size)][:sample_size]

    def one_process_each():
        for case in sample:
            through(shim, "imcpy-shim", suite, [case], EDITION)
    out["process per case"] = timed(one_process_each) * len(cases) / len(sample)
    COUNTS["subprocess"] = COUNTS["subprocess per line"] = len(cases)
    n = len(cases)
    print(f"subprocess, imcpy shim: batched {n / out['subprocess']:,.0f} cases/s, one a line "
          f"{n / out['subprocess per line']:,.0f} cases/s, one process per case {n / out['process per case']:,.0f} "
          f"cases/s (sampled)")
    return out | compiled_rows(suite, cases, repeat)


def compiled_rows(suite, cases, repeat: int) -> dict[str, float]:
    """The C++ programs through the subprocess session beside Python implementations through the same session:
    DUNE's codec against the imcpy shim (whole IMC corpus), roscpp against rosbags in a worker process (the
    ros_acomms corpus but for the cases roscpp crashes on by erratum C1, whose restarts would be timed)."""
    from ..suites.imc.dune.codec import argv as dune_argv
    from ..suites.ros_acomms.roscpp import argv as roscpp_argv

    ros, ros_cases = open_corpus("ros_acomms")
    ros_cases = [c for c in ros_cases if c.kind == "vector" and expectation(c.data, ROS_EDITION) is not None
                 and "C1" not in ros.implementation_errata(c.id, "roscpp")]
    worker = [sys.executable, "-m", "imc_conformance.sessions.worker", "--suite", "ros_acomms", "rosbags"]
    runs = {"subprocess dune-cpp": (suite, cases, EDITION, dune_argv()),
            "subprocess roscpp": (ros, ros_cases, ROS_EDITION, roscpp_argv()),
            "subprocess rosbags worker": (ros, ros_cases, ROS_EDITION, worker)}
    out = {}
    for row, (which, selected, edition, argv) in runs.items():
        out[row] = median_of(repeat, lambda: through(argv, row, which, selected, edition, hello_timeout=60))
        COUNTS[row] = len(selected)
    print(f"subprocess, compiled: DUNE's C++ codec {COUNTS['subprocess dune-cpp'] / out['subprocess dune-cpp']:,.0f} "
          f"cases/s ({len(cases)} IMC cases); roscpp {COUNTS['subprocess roscpp'] / out['subprocess roscpp']:,.0f} "
          f"cases/s against rosbags in a worker process "
          f"{COUNTS['subprocess rosbags worker'] / out['subprocess rosbags worker']:,.0f} cases/s "
          f"({len(ros_cases)} ros_acomms cases)")
    return out
