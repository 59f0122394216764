"""Benchmark: cases per second through the runner, IMC with imcpy in-process and through a subprocess, and
ros_acomms with rosbags and genpy in-process.

``python -m imc_conformance.benchmark [--repeat 5]`` prints medians over the repeats, all measured in
one run (these machines are noisy: compare the ratios, not absolute numbers across runs):

- library: the whole IMC corpus through ``run_cases`` with the imcpy library adapter (wall time
  excludes interpreter start and corpus loading, which are reported apart);
- imcpy alone: the same encode/decode calls made on imcpy directly, no adapter, no judging;
- subprocess: the whole corpus through the pipelined subprocess adapter and the imcpy shim;
- one process per case: the slow anchor, a fresh shim process for each case of a sample;
- ros_acomms: its whole corpus (seed edition) through ``run_cases`` with rosbags and with genpy, and
  rosbags' own calls made bare (deserialize every frame, serialize what it decoded);
- live: the whole IMC scenario set (seed profile, every effect allowed) against the reference node
  (``imc-conformance serve``) over loopback UDP, the same set on virtual time (the engine's own cost), and
  once, the robustness phase over loopback;
- capture: ``imc-conformance pcap`` on a generated capture of a million frames (heartbeats, LBL ranges,
  acoustic operations and requests with their statuses, Iridium transmissions; 5% damaged), whole command
  wall including the interpreter, reading the file and writing the JSON report; and reading alone (records
  and datagrams, no judging) for the ratio.
"""

from __future__ import annotations

import argparse
import statistics
import time

from .core.cases import expectation
from .core.runner import run_cases
from .files import open_corpus, read_cases

EDITION = "imc-5.4.30"
ROS_EDITION = "seed"
# (what, row, unit, bound): seconds must stay under the bound, cases/s must reach it.
TARGETS = (("whole corpus in-process", "library", "s", 2.0),
           ("in-process throughput", "library", "cases/s", 20_000),
           ("subprocess throughput", "subprocess", "cases/s", 5_000),
           ("scenario set against the reference node over loopback", "live", "s", 15.0),
           ("capture judged, whole command", "capture", "frames/s", 100_000),
           ("capture judged, whole command (floor)", "capture", "frames/s", 50_000))
CAPTURE_FRAMES = 1_000_000
LIVE_PARAMS = {"peer": "imc-peer-1", "beacon": "b1", "sms_number": "+351000000000", "remote_system": 8208}


def target_lines(medians: dict[str, float], counts: dict[str, int]) -> list[str]:
    """One line per target measured in this run, saying plainly whether it was met (``counts``: the cases or
    frames a row's seconds are for)."""
    lines = []
    for what, row, unit, bound in TARGETS:
        if row not in medians:
            continue
        if unit == "s":
            value, met, goal = medians[row], medians[row] < bound, f"< {bound:g} s"
            shown = f"{value:.3f} s"
        else:
            value = counts[row] / medians[row]
            met, goal, shown = value >= bound, f">= {bound:,} {unit}", f"{value:,.0f} {unit}"
        lines.append(f"target {what}: {shown} ({goal}): {'met' if met else 'MISSED'}")
    return lines


def imcpy_alone(suite, cases, emits: set[str]) -> float:
    """Seconds for the bare imcpy calls the corpus needs (decode via Packet.deserialize, encode via serialize)."""
    import imcpy

    frames, encodable = [], []
    for case in cases:
        for request in suite.kinds[case.kind].plan(case.data, EDITION, emits):
            if request.op in ("decode", "roundtrip"):
                frames.append(request.frame)
            if request.op in ("encode", "roundtrip") and case.data["expect"] == "valid":
                encodable.append(case.data["frames"]["le"])
    messages = [imcpy.Packet.deserialize(bytes.fromhex(f)) for f in encodable]
    start = time.perf_counter()
    for frame in frames:
        try:
            imcpy.Packet.deserialize(frame)
        except RuntimeError:
            pass
    for message in messages:
        message.serialize()
    return time.perf_counter() - start


def rosbags_alone(adapter, suite, cases) -> float:
    """Seconds for the bare rosbags calls the ROS corpus needs: deserialize every frame it decodes, serialize
    again what deserialized (no adapter conversion, no judging)."""
    work = []
    for case in cases:
        for request in suite.kinds[case.kind].plan(case.data, ROS_EDITION, {"ros1"}):
            if request.op == "decode":
                work.append((request.frame, adapter._typename(case.data["type"])))
    start = time.perf_counter()
    store = adapter.store
    for frame, typename in work:
        try:
            store.serialize_ros1(store.deserialize_ros1(frame, typename), typename)
        except Exception:  # a rejected frame costs what it costs
            pass
    return time.perf_counter() - start


def timed(fn) -> float:
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m imc_conformance.benchmark", description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--per-case-sample", type=int, default=40, help="cases run with one process each")
    parser.add_argument("--skip-subprocess", action="store_true")
    parser.add_argument("--skip-ros", action="store_true")
    parser.add_argument("--skip-live", action="store_true")
    parser.add_argument("--skip-robustness", action="store_true", help="no robustness phase over loopback")
    parser.add_argument("--skip-capture", action="store_true", help="no capture of a million frames")
    args = parser.parse_args(argv)

    from .adapters.imcpy_adapter import adapter
    from .sessions.library import LibrarySession
    from .sessions.subprocess import SubprocessSession

    suite, cases = open_corpus("imc")
    load = timed(lambda: (read_cases.cache_clear(), open_corpus("imc")))
    everything = cases
    cases = [c for c in cases if c.kind == "vector" and expectation(c.data, EDITION) is not None]
    library = LibrarySession(adapter(), "imcpy")
    shim = suite.adapters["imcpy-shim"].argv()

    def run(session, some, name):
        return run_cases(session, suite, some, edition=EDITION, adapter=name)

    rows: dict[str, list[float]] = {"library": [], "imcpy alone": [], "subprocess": [], "process per case": []}
    for _ in range(args.repeat):
        rows["library"].append(timed(lambda: run(library, cases, "imcpy")))
        rows["imcpy alone"].append(imcpy_alone(suite, cases, {"le"}))
        if not args.skip_subprocess:
            session = SubprocessSession(shim, name="imcpy-shim", encoding_param=suite.encoding_param)
            try:
                rows["subprocess"].append(timed(lambda: run(session, cases, "imcpy-shim")))
            finally:
                session.close()
            sample = cases[:: max(1, len(cases) // args.per_case_sample)][: args.per_case_sample]

            def one_process_each():
                for case in sample:
                    s = SubprocessSession(shim, name="imcpy-shim", encoding_param=suite.encoding_param)
                    try:
                        run(s, [case], "imcpy-shim")
                    finally:
                        s.close()
            rows["process per case"].append(timed(one_process_each) * len(cases) / len(sample))
    n = len(cases)
    med = {k: statistics.median(v) for k, v in rows.items() if v}
    print(f"corpus: {n} cases ({EDITION}); loading the vector files: {load:.3f} s; medians of {args.repeat} runs")
    for name, seconds in med.items():
        print(f"  {name:18s} {seconds:7.3f} s  {n / seconds:10,.0f} cases/s")
    overhead = (med["library"] - med["imcpy alone"]) / n * 1e6
    print(f"runner overhead over imcpy's own encode/decode: {overhead:.1f} µs per case "
          f"({med['library'] / med['imcpy alone']:.1f}x imcpy alone)")
    if "subprocess" in med:
        print(f"subprocess vs library: {med['subprocess'] / med['library']:.1f}x slower; "
              f"pipelined subprocess vs one process per case: {med['process per case'] / med['subprocess']:.0f}x faster")
    if not args.skip_ros:
        ros_rows(args.repeat)
    if not args.skip_live:
        med["live"] = live_rows(suite, everything, args.repeat, not args.skip_robustness)
    if not args.skip_capture:
        med["capture"] = capture_rows(suite, args.repeat)
    for line in target_lines(med, {"library": n, "subprocess": n, "capture": CAPTURE_FRAMES}):
        print(line)
    return 0



def ros_rows(repeat: int) -> None:
    """The ros_acomms corpus through the runner with rosbags and with genpy, and rosbags' calls made bare."""
    from .adapters.genpy_adapter import GenpyAdapter
    from .adapters.rosbags_adapter import RosbagsAdapter
    from .sessions.library import LibrarySession

    suite, cases = open_corpus("ros_acomms")
    cases = [c for c in cases if c.kind == "vector" and expectation(c.data, ROS_EDITION) is not None]
    adapters = {"rosbags": RosbagsAdapter(), "genpy": GenpyAdapter()}
    rows: dict[str, list[float]] = {"ros rosbags": [], "rosbags alone": [], "ros genpy": []}
    for _ in range(repeat):
        for name, adapter in adapters.items():
            session = LibrarySession(adapter, name)
            rows[f"ros {name}"].append(timed(lambda: run_cases(session, suite, cases, edition=ROS_EDITION, adapter=name)))
        rows["rosbags alone"].append(rosbags_alone(adapters["rosbags"], suite, cases))
    n = len(cases)
    med = {k: statistics.median(v) for k, v in rows.items()}
    print(f"ros_acomms corpus: {n} cases ({ROS_EDITION}); medians of {repeat} runs")
    for name, seconds in med.items():
        print(f"  {name:18s} {seconds:7.3f} s  {n / seconds:10,.0f} cases/s")
    print(f"runner with rosbags vs rosbags' bare calls: {med['ros rosbags'] / med['rosbags alone']:.1f}x; "
          f"genpy vs rosbags through the runner: {med['ros genpy'] / med['ros rosbags']:.2f}x")


def live_rows(suite, everything, repeat: int, robustness: bool) -> float:
    """The scenario set against the reference node over loopback (median seconds), and on virtual time; once,
    the robustness phase over loopback."""
    import re
    import subprocess
    import sys

    from .sessions.datagram import DatagramSession
    from .sessions.virtual import VirtualLink
    from .suites.imc.node import ReferenceNode
    from .suites.imc.peer import DEFAULT_SYSTEM, ImcPeer

    scenarios = [c for c in everything if c.kind == "scenario"]
    options = {"params": LIVE_PARAMS, "effects": {"all"}, "profile": suite.profile("seed"),
               "corpus": tuple(c for c in everything if c.kind == "vector")}
    node = subprocess.Popen([sys.executable, "-m", "imc_conformance.cli", "serve", "--port", "0"],
                            stderr=subprocess.PIPE, text=True)
    rows: dict[str, list[float]] = {"live": [], "virtual": []}
    verdicts = set()
    try:
        port = int(re.search(r"udp://127\.0\.0\.1:(\d+)", node.stderr.readline())[1])
        for _ in range(repeat):
            session = suite.open_target(f"udp://127.0.0.1:{port}")
            try:
                start = time.perf_counter()
                result = run_cases(session, suite, scenarios, edition=EDITION, adapter="udp", options=options)
                rows["live"].append(time.perf_counter() - start)
                verdicts |= set(result.summary)
            finally:
                session.close()
            reference = ReferenceNode(suite.defs, suite.behaviour, edition=EDITION, address=("127.0.0.1", 6002))
            link = VirtualLink(reference, ("127.0.0.1", 6002), ("127.0.0.1", 6001))
            peer = ImcPeer(suite.defs, system=DEFAULT_SYSTEM, node=None, service="imc+udp://127.0.0.1:6001/",
                           host="127.0.0.1", epoch=link.epoch)
            virtual = DatagramSession(link, peer, suite.wire, session.hello(), startup=10.0)
            rows["virtual"].append(timed(lambda: run_cases(virtual, suite, scenarios, edition=EDITION, adapter="virtual",
                                                           options=options, clock=link.now)))
        phase = None
        if robustness:
            probes = [c for c in everything if c.kind == "robustness"]
            session = suite.open_target(f"udp://127.0.0.1:{port}")
            try:
                start = time.perf_counter()
                result = run_cases(session, suite, probes, edition=EDITION, adapter="udp",
                                   options=dict(options, robustness=True))
                phase = (time.perf_counter() - start, result.summary)
            finally:
                session.close()
    finally:
        node.terminate()
        node.wait(timeout=10)
        node.stderr.close()
    med = {k: statistics.median(v) for k, v in rows.items()}
    print(f"live: {len(scenarios)} scenarios (seed profile, every effect allowed) against the reference node; "
          f"medians of {repeat} runs; verdicts seen: {', '.join(sorted(verdicts))}")
    print(f"  over loopback UDP   {med['live']:7.3f} s")
    print(f"  on virtual time     {med['virtual']:7.3f} s  (the engine and the node without the protocol's waits: "
          f"1/{med['live'] / med['virtual']:.0f} of the loopback run)")
    if phase is not None:
        print(f"  robustness phase over loopback (once): {phase[0]:.1f} s; verdicts {phase[1]}")
    return med["live"]


def capture_rows(suite, repeat: int) -> float:
    """``imc-conformance pcap`` on a generated capture of CAPTURE_FRAMES frames: median seconds of the whole
    command; reading alone for the ratio. The capture is written to a temporary folder and removed."""
    import subprocess
    import sys
    import tempfile
    from pathlib import Path

    from .capture.datagrams import Dissector
    from .capture.records import records
    from .suites.imc.traffic import write_capture

    with tempfile.TemporaryDirectory(prefix="imc-conformance-bench-") as folder:
        path, report = Path(folder) / "traffic.pcap", Path(folder) / "r.json"
        made = write_capture(path, suite.defs, suite.wire, EDITION, CAPTURE_FRAMES)
        rows: dict[str, list[float]] = {"whole": [], "reading": []}
        command = [str(Path(sys.executable).parent / "imc-conformance"), "pcap", str(path), "--json", str(report)]
        for _ in range(repeat):
            start = time.perf_counter()
            done = subprocess.run(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
            rows["whole"].append(time.perf_counter() - start)
            if done.returncode not in (0, 1):
                raise SystemExit(f"pcap failed ({done.returncode}): {done.stderr.strip()[:300]}")

            def read():
                dissector = Dissector()
                for record in records(path.read_bytes()):
                    dissector.datagram(record)
            rows["reading"].append(timed(read))
        size, report_bytes = path.stat().st_size, report.stat().st_size
    med = {k: statistics.median(v) for k, v in rows.items()}
    print(f"capture: {made['frames']:,} frames ({made['damaged']:,} damaged), {size / 1e6:.1f} MB pcap; medians of "
          f"{repeat} runs")
    print(f"  pcap command, whole {med['whole']:7.3f} s  {made['frames'] / med['whole']:10,.0f} frames/s "
          f"(JSON report {report_bytes / 1e3:.0f} kB)")
    print(f"  reading alone       {med['reading']:7.3f} s  {made['frames'] / med['reading']:10,.0f} frames/s "
          f"(judging costs {med['whole'] / med['reading']:.1f}x reading)")
    return med["whole"]


if __name__ == "__main__":
    raise SystemExit(main())
