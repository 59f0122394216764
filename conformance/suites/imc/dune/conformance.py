"""``make dune-conformance``: the whole IMC scenario set, with the robustness phase and every effect allowed, against
DUNE as a live node, under the ``seed`` profile and under the ``dune`` profile.

It runs inside a private network namespace it creates (``unshare -n``: loopback up, multicast routed to loopback,
nothing outside reachable), because DUNE announces itself on a multicast group and its acoustic modem simulator
talks over another. There it starts the Iridium gateway stand-in, DUNE's acoustic peer and DUNE as the vehicle,
runs ``imc-conformance run --target`` once per profile (vehicle and peer restarted fresh in between; the
robustness phase restarts both to bisect), then ``imc-conformance fuzz --target`` (live fuzzing, ``--fuzz-budget``
mutated frames a message, ``reports/dune-fuzz.{json,html}``), captures the exchange on loopback, stops everything it started by PID and checks that
no DUNE process is left. It writes ``reports/dune-<profile>.{json,html}``, the session's own recording of each run
``reports/dune-<profile>.pcapng`` (``imc-conformance pcap`` replays it) and everything on the IMC ports of loopback
(DUNE's traffic with its peer too) in ``reports/dune-exchange.pcap``, then runs
the expectations test (``tests/dune_expectations.py``: the verdict per message DUNE is known to get).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from contextlib import contextmanager
from pathlib import Path

from .build import built, home
from .world import (IRIDIUM_PORT, PEER, PEER_ID, UDP_PORT, VEHICLE, dune_argv, forget_state, iridium_gateway,
                    leftovers, restart, start, stop, write_configs)

INSIDE = "IMC_CONFORMANCE_DUNE_NAMESPACE"
PROFILES = ("seed", "dune")
CLAIMS = {"description": "What DUNE (lauv-simulator-1, as configured here) implements: no SmsTx (DUNE has only "
                         "SmsRequest, for a GSM modem on a serial port), no SystemGroup (no task handles it), and "
                         "AcousticRequest only from its own system, addressed to itself: the local API its tasks use to "
                         "reach the modem (src/Transports/UAN/Task.cpp:297-301); other systems use AcousticOperation.",
          "services": ["acoustic", "lbl", "iridium", "historic-data", "discovery"],
          "capabilities": {"acoustic-request": "self"}}
CAPTURED_PORTS = {UDP_PORT, *range(30100, 30105)}
FUZZ_BUDGET = 40
ACOUSTIC_WARMUP = 30.0  # seconds after a (re)start before DUNE's acoustic tasks and modem simulator serve requests


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="make dune-conformance", description=__doc__.splitlines()[0])
    parser.add_argument("--reports", type=Path, default=Path("reports"), help="where to write the reports")
    parser.add_argument("--no-robustness", action="store_true", help="the scenarios only (faster)")
    parser.add_argument("--fuzz-budget", type=int, default=FUZZ_BUDGET, metavar="N",
                        help=f"then live fuzzing: N mutated frames of each message's corpus frames, the robustness "
                             f"phase's probes and bisection (default {FUZZ_BUDGET}; 0: none)")
    parser.add_argument("--fuzz-only", action="store_true", help="only the live fuzzing (no scenario runs)")
    parser.add_argument("--checkout", type=Path, default=Path.cwd(), help="the checkout holding tests/")
    args = parser.parse_args(argv)
    done = entered(argv, "conformance", "make dune-conformance")
    return done if done is not None else _run(args)


def entered(argv: list[str], command_name: str, shown: str, terminable: bool = True) -> int | None:
    """None once a DUNE command (``command_name``) runs in its own private network namespace, isolated (a SIGTERM
    interrupting it when ``terminable``); else its exit code: 2 when DUNE is not built or the namespace is not
    private, or that of the command run again inside a namespace made for it."""
    if not built():
        print(f"{shown}: DUNE is not built here: run `make dune` first", file=sys.stderr)
        return 2
    if os.environ.get(INSIDE) != "1":
        return _in_namespace(argv, command_name)
    if terminable:
        signal.signal(signal.SIGTERM, _interrupted)
    problem = _isolate()
    if problem:
        print(f"{shown}: {problem}", file=sys.stderr)
        return 2
    return None


def _in_namespace(argv: list[str], command_name: str = "conformance") -> int:
    """Run this same command again inside a new network namespace."""
    if shutil.which("unshare") is None or shutil.which("ip") is None:
        print("make dune-conformance: needs unshare and ip (Debian: util-linux, iproute2)", file=sys.stderr)
        return 2
    probe = subprocess.run(["unshare", "--net", "true"], capture_output=True, text=True)
    if probe.returncode != 0:
        print(f"make dune-conformance: cannot create a network namespace ({probe.stderr.strip()}): unshare --net "
              "needs root", file=sys.stderr)
        return 2
    command = ["unshare", "--net", "--", sys.executable, "-m", "imc_conformance.suites.imc.dune", command_name, *argv]
    inner = subprocess.Popen(command, env={**os.environ, INSIDE: "1"})  # unshare execs it: this is its process
    signal.signal(signal.SIGTERM, lambda signum, frame: inner.send_signal(signal.SIGTERM))
    while True:
        try:
            return inner.wait()
        except KeyboardInterrupt:  # Ctrl-C reached it too (same process group): let it write and stop
            continue


def _interrupted(signum, frame):
    raise KeyboardInterrupt  # so that a SIGTERM (make, a timeout) writes what was judged and stops what was started


def _run(args) -> int:
    args.reports.mkdir(parents=True, exist_ok=True)
    began = time.monotonic()
    codes = {}
    with _world(args.reports / "dune-exchange.pcap") as run:
        (run / "claims.json").write_text(json.dumps(CLAIMS))
        try:
            for i, profile in enumerate(() if args.fuzz_only else PROFILES):
                if i:
                    _restart_both(run)
                codes[profile] = _suite(args, run, profile)
                if codes[profile] == 130:  # the run was interrupted (Ctrl-C, SIGTERM): so is the whole job
                    raise KeyboardInterrupt
            if args.fuzz_budget:
                if codes:
                    _restart_both(run)
                time.sleep(ACOUSTIC_WARMUP)  # the probes' baseline needs the acoustic service up, which DUNE starts late
                codes["fuzz"] = _fuzz(args, run)
                if codes["fuzz"] == 130:
                    raise KeyboardInterrupt
        except KeyboardInterrupt:
            print("make dune-conformance: interrupted", file=sys.stderr)
            return 130
    wall = time.monotonic() - began
    print(f"wall time: {wall:.0f} s; exit codes: " + ", ".join(f"{p} {c}" for p, c in codes.items()))
    (args.reports / "dune-run.json").write_text(json.dumps({"wall_seconds": round(wall), "exit_codes": codes}) + "\n")
    if any(code not in (0, 1) for code in codes.values()):
        return 2  # a run that could not judge DUNE (usage, adapter, nothing tested)
    return 0 if args.fuzz_only else _expectations(args)


@contextmanager
def _world(capture_to: Path, record_to: int | None = None, per_message: int | None = None):
    """The vehicle, its peer and the Iridium gateway started (``write_configs(record_to)``), their state forgotten,
    with the IMC ports of loopback captured; the run folder. On the way out everything is stopped, the capture
    written to ``capture_to`` (``per_message``: see ``_save_capture``) and any DUNE process left over killed."""
    stale = leftovers()
    for pid in stale:
        os.kill(pid, signal.SIGKILL)
    if stale:
        print(f"killed {len(stale)} DUNE processes left over by an earlier run")
    run = home() / "run"
    shutil.rmtree(run, ignore_errors=True)
    run.mkdir(parents=True)
    write_configs(record_to)
    for system in (VEHICLE, PEER):
        forget_state(system)
    gateway, capture = iridium_gateway(), _capture()
    start(run, "peer", dune_argv("peer"))
    start(run, "vehicle", dune_argv("vehicle"))
    try:
        yield run
    finally:
        for name in ("vehicle", "peer"):
            stop(run, name)
        gateway.shutdown()
        _save_capture(capture, capture_to, per_message)
        left = leftovers()
        for pid in left:
            os.kill(pid, signal.SIGKILL)
        print(f"stopped: the vehicle, its peer and the gateway; {'no DUNE process left' if not left else f'killed {len(left)} left over'}")


def _isolate() -> str | None:
    """Bring loopback up and route multicast to it; why the namespace is not private, or None."""
    lines = Path("/proc/net/dev").read_text().splitlines()[2:]  # this namespace's interfaces (sysfs shows the host's)
    interfaces = sorted(line.split(":", 1)[0].strip() for line in lines)
    if interfaces != ["lo"]:
        return f"not in a private network namespace (interfaces: {', '.join(interfaces)})"
    for command in (["ip", "link", "set", "lo", "up"], ["ip", "link", "set", "lo", "multicast", "on"],
                    ["ip", "route", "add", "224.0.0.0/4", "dev", "lo"]):
        done = subprocess.run(command, capture_output=True, text=True)
        if done.returncode != 0:
            return f"{' '.join(command)}: {done.stderr.strip()}"
    return None


def _suite(args, run: Path, profile: str) -> int:
    """One run of the scenario set against the vehicle, under ``profile``; its exit code."""
    from ....cli import main as cli

    restart_cmd = f"{sys.executable} -m imc_conformance.suites.imc.dune restart --run {run}"
    argv = ["run", "--no-progress", "--target", f"udp://127.0.0.1:{UDP_PORT}", "--startup", "40",
            "--allow-effects", "--claims", str(run / "claims.json"), "--profile", profile,
            "--param", f"peer={PEER}", "--param", f"beacon={PEER}", "--param", "sms_number=+351000000000",
            "--param", f"remote_system={PEER_ID:#06x}", "--param", f"gateway=http://127.0.0.1:{IRIDIUM_PORT}/",
            "--json", str(args.reports / f"dune-{profile}.json"), "--html", str(args.reports / f"dune-{profile}.html"),
            "--pcap", str(args.reports / f"dune-{profile}.pcapng")]
    if not args.no_robustness:  # a simulated vehicle: the corpus's own destinations are harmless here
        argv += ["--robustness", "--replay-effects", "--restart-cmd", restart_cmd]
    print(f"== {profile} profile: imc-conformance {' '.join(argv)}", flush=True)
    return cli(argv)


def _fuzz(args, run: Path) -> int:
    """Live fuzzing of the vehicle: mutated requests of every message in place of the corpus in the robustness phase
    (seed 0, ``--fuzz-budget`` frames a message), both restarted to bisect; its exit code."""
    from ....cli import main as cli

    argv = ["fuzz", "--target", f"udp://127.0.0.1:{UDP_PORT}", "--startup", "40", "--allow-effects", "--replay-effects",
            "--restart-cmd", f"{sys.executable} -m imc_conformance.suites.imc.dune restart --run {run}",
            "--param", f"peer={PEER}", "--param", f"beacon={PEER}", "--param", "sms_number=+351000000000",
            "--param", f"remote_system={PEER_ID:#06x}", "--param", f"gateway=http://127.0.0.1:{IRIDIUM_PORT}/", "--seed", "0", "--budget", str(args.fuzz_budget),
            "--json", str(args.reports / "dune-fuzz.json"), "--html", str(args.reports / "dune-fuzz.html")]
    print(f"== live fuzzing: imc-conformance {' '.join(argv)}", flush=True)
    return cli(argv)


def _capture():
    """A sniffer of the IMC datagrams on loopback (scapy), or None when it cannot run."""
    try:
        from scapy.all import UDP, AsyncSniffer
    except ImportError:
        print("no capture: scapy is not installed")
        return None

    def ours(packet) -> bool:
        return UDP in packet and ({packet[UDP].sport, packet[UDP].dport} & CAPTURED_PORTS)
    sniffer = AsyncSniffer(iface="lo", lfilter=ours, store=True)
    sniffer.start()
    return sniffer


def _save_capture(sniffer, path: Path, per_message: int | None = None) -> None:
    """Write what the sniffer saw (``per_message``: at most that many datagrams of each IMC message id)."""
    if sniffer is None:
        return
    from scapy.all import UDP, wrpcap

    packets, previous, seen = [], None, {}
    for packet in sniffer.stop():  # a packet socket on loopback sees each packet twice, leaving and arriving
        data = bytes(packet)
        if data != previous:
            payload = bytes(packet[UDP].payload)
            key = payload[2:4] if payload[:2] == b"\x54\xfe" else payload[3:1:-1]  # the message id, little-endian
            seen[key] = seen.get(key, 0) + 1
            if per_message is None or seen[key] <= per_message:
                packets.append(packet)
        previous = None if data == previous else data
    wrpcap(str(path), packets)
    print(f"capture: {len(packets)} datagrams in {path}")


def _expectations(args) -> int:
    """The expectations test over the reports just written."""
    test = args.checkout / "tests" / "dune_expectations.py"
    if not test.exists():
        print(f"no expectations test at {test} (run from the checkout)")
        return 0
    env = {**os.environ, "IMC_CONFORMANCE_DUNE_REPORTS": str(args.reports.resolve())}
    return subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(test)],
                          cwd=args.checkout, env=env).returncode


def _restart_both(run: Path) -> None:
    """Restart the peer and then the vehicle, both with their state forgotten: the vehicle's acoustic stack keeps
    state about its peer (a pending operation, the modem's busy flag) that a vehicle-only restart leaves stale."""
    restart(run, "peer", PEER)
    restart(run, "vehicle", VEHICLE)


def restart_world(argv: list[str]) -> int:
    """``--restart-cmd`` of the robustness phase: restart the vehicle and its acoustic peer (state forgotten)."""
    parser = argparse.ArgumentParser(prog="python -m imc_conformance.suites.imc.dune restart")
    parser.add_argument("--run", type=Path, required=True)
    args = parser.parse_args(argv)
    _restart_both(args.run)
    return 0



RECORD_PORT = 6001  # where the vehicle sends its traffic in a recording: one of the IMC ports the capture keeps


def record(argv: list[str]) -> int:
    """``python -m imc_conformance.suites.imc.dune record``: DUNE's whole traffic for some seconds, in a recording.

    The vehicle and its peer run as for the scenarios (in a private network namespace), but the vehicle sends DUNE's
    own list of transported messages (lauv-simulator-1's: estimated state, entity states, CPU usage, plans...) to a
    socket on loopback; everything on the IMC ports is recorded (pcap). The mission log the vehicle's Logging task
    wrote meanwhile (Data.lsf.gz, with the IMC.xml.gz it was built with) is moved out of DUNE's folder into
    ``--log-out``."""
    parser = argparse.ArgumentParser(prog="python -m imc_conformance.suites.imc.dune record",
                                     description=record.__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=120.0, help="how long to record (default 120)")
    parser.add_argument("--out", type=Path, default=Path("reports/dune-whole.pcap"), help="the recording to write")
    parser.add_argument("--per-message", type=int, metavar="N",
                        help="keep at most N datagrams of each message (a small recording of every message sent)")
    parser.add_argument("--log-out", type=Path, default=Path("reports/dune-log"),
                        help="where to move the vehicle's mission log folders (default reports/dune-log)")
    args = parser.parse_args(argv)
    done = entered(argv, "record", "dune record", terminable=False)
    if done is not None:
        return done
    import socket

    args.out.parent.mkdir(parents=True, exist_ok=True)
    sink = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sink.bind(("127.0.0.1", RECORD_PORT))
    sink.settimeout(0.5)
    received = 0
    try:
        with _world(args.out, record_to=RECORD_PORT, per_message=args.per_message):
            end = time.monotonic() + args.seconds
            while time.monotonic() < end:
                try:
                    sink.recv(65536)
                    received += 1
                except socket.timeout:
                    continue
    except KeyboardInterrupt:
        print("dune record: interrupted", file=sys.stderr)
    finally:
        sink.close()
    kept = _keep_logs(home() / "run" / "vehicle.log", args.log_out)
    print(f"dune record: {received} datagrams from the vehicle in {args.seconds:g} s; its mission log: "
          + (", ".join(str(p) for p in kept) or "none written"))
    return 0 if received and kept else 1


LOG_LINES = re.compile(r">> log (?:folder: '(?P<folder>[^']+)'|started '(?P<started>\d{8}/\d{6}(?:_[\w.-]+)?)')")
CONSOLE_LIMIT = 16 << 20  # bytes of DUNE's console output read for the lines naming its logs (they come first)


def _keep_logs(console: Path, out: Path) -> list[Path]:
    """Move the log folders a DUNE process says it started (in its console output) into ``out``; the folders. DUNE
    is under test: only a folder under its own home, named as its Logging task names them (date/time), is moved."""
    kept, folder = [], None
    try:
        with open(console, "rb") as handle:
            text = handle.read(CONSOLE_LIMIT).decode(errors="replace")
    except OSError:
        return kept
    for line in text.splitlines():
        found = LOG_LINES.search(line)
        if found and found["folder"]:
            folder = Path(found["folder"]).resolve()
            folder = folder if folder.is_relative_to(home().resolve()) else None
        elif found and found["started"] and folder is not None and (folder / found["started"]).is_dir():
            target = out / found["started"]
            shutil.rmtree(target, ignore_errors=True)
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.move(str(folder / found["started"]), target)
            kept.append(target)
    return kept
