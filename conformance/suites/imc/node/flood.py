"""Benchmark rows: the reference node (``imc-conformance serve``, a whole process on loopback) under a console's flood
of HistoricSamples in 60 kB datagrams, each followed by a QUERY: how long the replies take and the node's peak memory
(its store is bounded: history.py). ``python -m imc_conformance.suites.imc.node.flood [SAMPLES ...]`` prints them.
"""

from __future__ import annotations

import re
import select
import socket
import statistics
import subprocess
import sys
import time
from pathlib import Path

PER_DATAGRAM = 4000  # HistoricSamples holding no sample: 15 bytes each, a 60 kB datagram
CONSOLE_ID, NODE_ID = 0x3001, 0x00A0
FLOODS = (68_000, 1_000_000)  # the flood, and one fifteen times larger
SYNC_EVERY = 2  # datagrams between QUERYs, each waiting for its reply: what a default socket buffer (208 kB) holds
REPLY_WAIT = 60.0  # seconds a reply is waited for before the node is called stalled


def flood_rows(floods=FLOODS) -> dict[str, float]:
    """Per flood of N samples: the slowest and the median reply to a QUERY of max_size 65,535 while it lasts
    (``node flood reply N``, ``node flood median reply N``, seconds) and the node's peak resident memory
    (``node flood memory N``, MB), beside the node's own at rest (``node flood memory 0``) and as a ratio to it
    (``node flood memory ratio``, the largest flood's)."""
    from .. import codec, load

    suite = load()
    out = {}
    for samples in floods:
        node = subprocess.Popen([sys.executable, "-m", "imc_conformance.cli", "serve", "--port", "0"],
                                stderr=subprocess.PIPE, text=True)
        try:
            line = node.stderr.readline()
            listening = re.search(r"udp://([\d.]+):(\d+)", line)
            if listening is None:
                raise SystemExit(f"the reference node did not say where it listens: {line.strip() or 'nothing'}")
            host, port = listening.groups()
            out["node flood memory 0"] = peak_mb(node.pid)
            replies = flood(suite.defs, codec, (host, int(port)), samples)
            out[f"node flood reply {samples}"] = max(replies)
            out[f"node flood median reply {samples}"] = statistics.median(replies)
            out[f"node flood memory {samples}"] = peak_mb(node.pid)
            alive = node.poll() is None
        finally:
            node.terminate()
            node.wait(timeout=10)
            node.stderr.close()
        if not alive:
            raise SystemExit(f"the reference node died under a flood of {samples:,} samples")
        out["node flood memory ratio"] = out[f"node flood memory {samples}"] / out["node flood memory 0"]
        print(f"node flood: {samples:,} samples in {-(-samples // PER_DATAGRAM)} datagrams of 60 kB, {len(replies)} "
              f"QUERYs (max_size 65,535): slowest reply {max(replies) * 1e3:.1f} ms, median "
              f"{statistics.median(replies) * 1e3:.1f} ms; peak memory {out[f'node flood memory {samples}']:.1f} MB "
              f"(at rest {out['node flood memory 0']:.1f} MB)")
    return out


def flood(defs, codec, node: tuple[str, int], samples: int) -> list[float]:
    """Announce a console to the node, send it ``samples`` samples, a QUERY every ``SYNC_EVERY`` datagrams and one
    at the end; the seconds each QUERY's reply took."""
    console = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    console.bind(("127.0.0.1", 0))
    try:
        def frame(abbrev: str, fields: dict) -> bytes:
            header = {"timestamp": time.time(), "src": CONSOLE_ID, "src_ent": 0, "dst": NODE_ID, "dst_ent": 255}
            return codec.encode(defs, {"abbrev": abbrev, "header": header, "fields": fields}, "le")

        announce = {"sys_name": "flood-console", "sys_type": 0, "owner": 0xFFFF, "lat": 0.0, "lon": 0.0,
                    "height": 0.0, "services": f"imc+udp://127.0.0.1:{console.getsockname()[1]}/"}
        console.sendto(frame("Announce", announce), node)
        replies = []
        sent = 0
        while sent < samples:
            k = min(PER_DATAGRAM, samples - sent)
            items = [{"abbrev": "HistoricSample", "fields": {"sys_id": CONSOLE_ID, "priority": (sent + i) % 7 - 3,
                                                             "x": i, "y": 0, "z": 0, "t": 0, "sample": None}}
                     for i in range(k)]
            console.sendto(frame("HistoricData", {"base_lat": 0.0, "base_lon": 0.0, "base_time": 0.0, "data": items}),
                           node)
            sent += k
            if sent >= samples or (sent // PER_DATAGRAM) % SYNC_EVERY == 0:
                replies.append(query(codec, defs, console, node, frame, len(replies)))
        return replies
    finally:
        console.close()


def query(codec, defs, console, node, frame, req_id: int) -> float:
    """Seconds from a QUERY (max_size 65,535) to its reply."""
    start = time.perf_counter()
    console.sendto(frame("HistoricDataQuery", {"req_id": req_id, "type": 1, "max_size": 65535, "data": None}), node)
    while time.perf_counter() - start < REPLY_WAIT:
        ready, _, _ = select.select([console], [], [], 1.0)
        if not ready:
            continue
        data = console.recv(65535)
        try:
            message = codec.decode(defs, data)
        except ValueError:
            continue
        if message["abbrev"] == "HistoricDataQuery" and message["fields"]["req_id"] == req_id:
            return time.perf_counter() - start
    raise SystemExit(f"the reference node answered no QUERY within {REPLY_WAIT:.0f} s")


def peak_mb(pid: int) -> float:
    """A process's peak resident memory (Linux: VmHWM), in MB."""
    status = Path(f"/proc/{pid}/status").read_text()
    return int(re.search(r"VmHWM:\s+(\d+) kB", status)[1]) / 1024


if __name__ == "__main__":
    for row, value in flood_rows(tuple(int(n) for n in sys.argv[1:]) or FLOODS).items():
        print(f"{row}: {value:.3f}")
