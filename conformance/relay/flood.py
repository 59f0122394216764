"""The relay under a console's flood, measured for the benchmark: ``imc-conformance relay --impair delay=2`` (every
datagram held 2 s, so a relay that bounded nothing would hold two seconds of the flood) while a console sends
65,507-byte datagrams (the largest a UDP datagram holds) as fast as it can; the relay's peak resident memory, measured
from a small process that starts it (a process forked from the benchmark's would count the benchmark's memory), beside
what was sent and what the relay's bound on what a direction holds in flight (``core.IN_FLIGHT_LIMIT``) dropped."""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from .core import IN_FLIGHT_LIMIT

DATAGRAM = 65_507  # bytes: the most one UDP datagram over IPv4 carries
SECONDS = 10.0
# Starts a command and prints its exit code and its peak resident memory (KiB), once it has ended.
MEASURE = ("import resource, subprocess, sys; code = subprocess.call(sys.argv[1:], stdout=subprocess.DEVNULL, "
           "stderr=subprocess.DEVNULL); print(code, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)")


def _port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def relay_flood(seconds: float = SECONDS, env: dict | None = None) -> dict[str, float]:
    """Flood the relay for ``seconds``; its peak memory (MB), the datagrams the console sent and those the relay
    read, and those its in-flight bound dropped."""
    listen, via = _port(), _port()
    with tempfile.TemporaryDirectory(prefix="imc-conformance-relay-flood-") as folder, \
            socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as vehicle, \
            socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as console:
        vehicle.bind(("127.0.0.1", 0))
        report = Path(folder) / "relay.json"
        argv = [sys.executable, "-m", "imc_conformance.cli", "relay", f"udp://127.0.0.1:{listen}", "--vehicle",
                f"udp://127.0.0.1:{vehicle.getsockname()[1]}", "--via", f"127.0.0.1:{via}", "--impair", "delay=2",
                "--duration", f"{seconds + 3:g}", "--json", str(report)]
        measuring = subprocess.Popen([sys.executable, "-c", MEASURE, *argv], stdout=subprocess.PIPE, text=True,
                                     env=env, cwd=folder)
        try:
            time.sleep(2.0)  # the relay's start
            vehicle.sendto(b"vehicle", ("127.0.0.1", via))  # it hears from the vehicle once
            payload = bytearray(os.urandom(DATAGRAM))
            sent, end = 0, time.monotonic() + seconds
            while time.monotonic() < end:
                payload[:4] = sent.to_bytes(4, "little")  # each datagram its own bytes
                try:
                    console.sendto(payload, ("127.0.0.1", listen))
                    sent += 1
                except OSError:  # the kernel's buffers full a moment
                    time.sleep(0.001)
            try:
                out, _ = measuring.communicate(timeout=seconds + 120)
            except subprocess.TimeoutExpired:
                raise SystemExit(f"relay under a flood did not end within {seconds + 120:g} s") from None
        finally:
            if measuring.poll() is None:
                measuring.kill()
                measuring.wait()
        if len(out.split()) != 2:  # the measuring process ended before it could print
            raise SystemExit(f"relay under a flood: no exit code and peak memory measured ({out.strip() or 'nothing'})")
        code, peak = out.split()
        if int(code) not in (0, 1, 2) or not report.exists():  # 2: a flood of no frames judges nothing
            raise SystemExit(f"relay under a flood ended with exit code {code} and no report")
        notes = json.loads(report.read_text(encoding="utf-8"))["notes"]
    line = next(n for n in notes if n.startswith("console to vehicle:"))
    read = int(line.split(": ", 1)[1].split()[0])
    dropped = next((int(part.split()[0]) for part in line.split("; ")[1].split(", ") if "in flight" in part), 0) \
        if "; " in line else 0
    return {"peak MB": int(peak) * 1024 / 1e6, "sent": sent, "read": read, "bound dropped": dropped}


def flood_rows(env: dict | None = None) -> dict[str, float]:
    """The benchmark's row: the relay's peak memory (MB) under the flood; prints what it measured."""
    got = relay_flood(env=env)
    print(f"relay flood: --impair delay=2, {got['sent']:,} datagrams of {DATAGRAM:,} bytes sent in {SECONDS:g} s "
          f"({got['sent'] * DATAGRAM / 1e9:.1f} GB), {got['read']:,} read by the relay, {got['bound dropped']:,} "
          f"dropped by its {IN_FLIGHT_LIMIT >> 20} MiB in-flight bound per direction; peak memory {got['peak MB']:.0f} MB")
    return {"relay flood": got["peak MB"]}
