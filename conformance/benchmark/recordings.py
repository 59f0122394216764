"""Recordings judged: a generated capture (``pcap``) and LSF logs grown from DUNE's (``log``), whole commands."""

from __future__ import annotations

import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from .measure import CAPTURE_FRAMES, COUNTS, EDITION, command, command_env, median_of, whole


def capture_rows(suite, repeat: int) -> dict[str, float]:
    """``imc-conformance pcap`` on a generated capture of CAPTURE_FRAMES frames (whole command), and reading alone."""
    from ..capture.datagrams import Dissector
    from ..capture.records import records
    from ..suites.imc.traffic import write_capture

    with tempfile.TemporaryDirectory(prefix="imc-conformance-bench-") as folder:
        path, report = Path(folder) / "traffic.pcap", Path(folder) / "r.json"
        made = write_capture(path, suite.defs, suite.wire, EDITION, CAPTURE_FRAMES)
        out = {"capture": median_of(repeat, lambda: whole(["pcap", str(path), "--json", str(report)], command_env()))}

        def read():
            dissector = Dissector()
            for record in records(path.read_bytes()):
                dissector.datagram(record)
        out["capture reading"] = median_of(repeat, read)
    COUNTS["capture"] = made["frames"]
    print(f"capture: {made['frames']:,} frames ({made['damaged']:,} damaged): pcap, whole command "
          f"{out['capture']:.3f} s ({made['frames'] / out['capture']:,.0f} frames/s); reading alone "
          f"{out['capture reading']:.3f} s (judging costs {out['capture'] / out['capture reading']:.1f}x reading)")
    return out


LOG_FRAMES = 1_000_000
LOG_SIZES = (("100 MB", 100 << 20), ("1 GB", 1 << 30))  # logs whose peak memory is compared
LOG_EXCERPT = Path(__file__).resolve().parents[2] / "tests" / "data" / "dune-log" / "Data.lsf.gz"


# Runs a command and says its resources: measured from a small process, since a child forked from this one counts the
# benchmark's own memory as its peak until it runs the command.
MEASURE = ("import resource, subprocess, sys; code = subprocess.call(sys.argv[1:], stdout=subprocess.DEVNULL, "
           "stderr=subprocess.DEVNULL); use = resource.getrusage(resource.RUSAGE_CHILDREN); "
           "print(use.ru_utime + use.ru_stime, use.ru_maxrss, code)")


def measured(argv: list[str]) -> tuple[float, float, int]:
    """(seconds, CPU seconds, peak resident memory in bytes) of one whole command (exit code 0 or 1 expected): the CPU
    time shows what contention with other work on the machine hides in the seconds."""
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-c", MEASURE, *command(argv)],
                          capture_output=True, text=True, env=command_env(), cwd=tempfile.gettempdir())
    took = time.perf_counter() - start
    cpu, peak, code = done.stdout.split()
    if int(code) not in (0, 1):
        raise SystemExit(f"imc-conformance {' '.join(argv)} failed ({code})")
    return took, float(cpu), int(peak) * 1024


def log_rows(repeat: int) -> dict[str, float]:
    """``imc-conformance log`` on LSF logs grown from DUNE's recorded log (with the IMC.xml beside them): a million
    frames uncompressed and gzip (whole command), and the peak memory on ~100 MB and ~1 GB logs."""
    import gzip

    from ..suites.imc.imc_xml import fetch_imc_xml
    from ..suites.imc.traffic import grow_log

    if not LOG_EXCERPT.exists():
        print(f"logs: no recorded log at {LOG_EXCERPT} (run from a checkout): skipped")
        return {}
    recorded = gzip.decompress(LOG_EXCERPT.read_bytes())
    out = {}
    with tempfile.TemporaryDirectory(prefix="imc-conformance-logs-") as folder:
        folder = Path(folder)
        (folder / "gz").mkdir()
        for where in (folder, folder / "gz"):
            (where / "IMC.xml.gz").write_bytes(gzip.compress(fetch_imc_xml().read_bytes()))
        once = grow_log(recorded, folder / "Data.lsf", 1)  # the recording once: its frames
        made = grow_log(recorded, folder / "Data.lsf", LOG_FRAMES * once["bytes"] // once["frames"])
        with open(folder / "Data.lsf", "rb") as plain, gzip.open(folder / "gz" / "Data.lsf.gz", "wb") as packed:
            while piece := plain.read(1 << 20):
                packed.write(piece)
        COUNTS["log"] = made["frames"]
        for row, path in (("log", folder / "Data.lsf"), ("log gzip", folder / "gz" / "Data.lsf.gz")):
            runs = [measured(["log", str(path)]) for _ in range(repeat)]
            out[row], out[f"{row} cpu"] = statistics.median(r[0] for r in runs), statistics.median(r[1] for r in runs)
        out["log gzip ratio"] = out["log gzip"] / out["log"]
        sizes = {}
        for label, size in LOG_SIZES:
            (folder / "Data.lsf").unlink()
            grown = grow_log(recorded, folder / "Data.lsf", size)
            out[f"log {label} seconds"], _, sizes[label] = measured(["log", str(folder / "Data.lsf")])
            COUNTS[f"log {label}"] = grown["frames"]
        out["log memory ratio"] = sizes["1 GB"] / sizes["100 MB"]
    n = COUNTS["log"]
    print(f"logs: {n:,} frames of DUNE's log ({made['bytes'] / 1e6:.0f} MB): uncompressed {out['log']:.2f} s "
          f"({n / out['log']:,.0f} frames/s; CPU {out['log cpu']:.2f} s, {n / out['log cpu']:,.0f} frames/s), gzip "
          f"{out['log gzip']:.2f} s ({out['log gzip ratio']:.2f}x; CPU {out['log gzip cpu']:.2f} s, "
          f"{out['log gzip cpu'] / out['log cpu']:.2f}x); peak memory {sizes['100 MB'] / 2**20:.0f} MB for 100 MB "
          f"({COUNTS['log 100 MB']:,} frames, {out['log 100 MB seconds']:.0f} s), {sizes['1 GB'] / 2**20:.0f} MB for "
          f"1 GB ({COUNTS['log 1 GB']:,} frames, {out['log 1 GB seconds']:.0f} s): {out['log memory ratio']:.2f}x")
    return out
