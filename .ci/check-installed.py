"""Run both suites from an installed wheel, in a folder outside the checkout, and check what they find.

Usage: python check-installed.py BIN_DIR CAPTURE — BIN_DIR holds the installed ``imc-conformance``; CAPTURE is a
recording to judge (tests/data/dune-seed.pcapng; DUNE's mission log beside it, dune-log/Data.lsf.gz, is judged too).
Every failure of the real implementations must be a documented erratum, every case the corpus lists must be run, the
reference node must pass over loopback, and the capture and the log must be read. Exits 1 with the reasons
otherwise.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
import tempfile
from pathlib import Path

BIN = Path(sys.argv[1])
CAPTURE = Path(sys.argv[2])
PARAMS = ["--param", "peer=imc-peer-1", "--param", "beacon=b1", "--param", "sms_number=+351000000000",
          "--param", "remote_system=8208"]
problems: list[str] = []


def run(*argv: str, ok=(0,)) -> subprocess.CompletedProcess:
    done = subprocess.run([str(BIN / "imc-conformance"), *argv], capture_output=True, text=True, timeout=900)
    if done.returncode not in ok:
        problems.append(f"imc-conformance {' '.join(argv)}: exit {done.returncode}: {done.stderr.strip()[-500:]}")
    return done


def judged(report: Path, what: str, listed: int | None = None, explained: bool = True) -> None:
    """Check a saved result: its failures explained by errata (``explained``), its cases as many as listed."""
    doc = json.loads(report.read_text())
    cases = [c for m in doc["messages"] for c in m["cases"]]
    unexplained = [c["id"] for c in cases
                   if c["verdict"] in ("FAIL", "CRASH", "TIMEOUT", "ADAPTER_ERROR") and not c.get("errata")]
    if explained and unexplained:
        problems.append(f"{what}: {len(unexplained)} failures no erratum explains, e.g. {unexplained[:3]}")
    if listed is not None and len(cases) != listed:
        problems.append(f"{what}: {len(cases)} cases judged, the corpus lists {listed}")
    print(f"{what}: {len(cases)} cases, {doc['summary']}")


with tempfile.TemporaryDirectory() as folder:
    here = Path(folder)
    print(run("--version").stdout.strip())
    # the compiled adapters are built from the wheel's C++ sources, into the cache, on first use
    for suite, adapter in (("imc", "imcpy"), ("imc", "imcpy-shim"), ("imc", "dune-cpp"), ("imc-full", "imcpy"),
                           ("ros_acomms", "rosbags"), ("ros_acomms", "roscpp")):
        listed = sum("/scenario/" not in line and "/robustness/" not in line  # a library adapter runs the vectors
                     for line in run("list", "--suite", suite).stdout.splitlines())
        report = here / f"{adapter}{'-full' if suite == 'imc-full' else ''}.json"
        run("run", "--suite", suite, "--adapter", adapter, "--no-progress", "--json", str(report), ok=(0, 1))
        judged(report, f"{suite} with {adapter}", listed)
    node = subprocess.Popen([str(BIN / "imc-conformance"), "serve", "--port", "0"], stderr=subprocess.PIPE, text=True)
    try:
        url = re.search(r"udp://\S+?(?=[;,])", node.stderr.readline())[0]
        report = here / "live.json"
        run("run", "--target", url, "--allow-effects", *PARAMS, "--no-progress", "--json", str(report))
        judged(report, f"the scenarios against serve at {url}")
    finally:
        node.terminate()
        node.wait(timeout=30)
    report = here / "capture.json"
    run("pcap", str(CAPTURE), "--json", str(report), ok=(0, 1))
    judged(report, f"the capture {CAPTURE.name} (DUNE's own failures in it)", explained=False)
    log = CAPTURE.parent / "dune-log" / "Data.lsf.gz"  # DUNE's own mission log: every frame valid
    report = here / "log.json"
    run("log", str(log), "--json", str(report))
    judged(report, f"DUNE's mission log {log.parent.name}/{log.name}")
    report = here / "fuzz.json"  # a library adapter in its worker process, from the wheel: every finding explained
    run("fuzz", "--adapter", "imcpy", "--adapter", "pyimclsts", "--message", "LblRange", "--budget", "40",
        "--json", str(report))
    judged(report, "fuzzing LblRange, imcpy against pyimclsts")
    mutants = run("mutants", "--mutant", "crc-ccitt", "--mutant", "trims-trailing-spaces", "--mutant", "le-only").stdout
    print(mutants.strip().splitlines()[-1])
    matrix = here / "matrix.md"
    run("matrix", str(here / "imcpy.json"), str(here / "rosbags.json"), str(report), "--markdown", str(matrix))
    if matrix.read_text().count("## ") != 2:
        problems.append("the matrix of an IMC and a ros_acomms result does not hold two tables")

if problems:
    print("\n".join(problems), file=sys.stderr)
    sys.exit(1)
print("the installed wheel runs both suites")
