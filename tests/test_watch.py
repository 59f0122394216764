"""The passive monitor: judging what is sent to a socket on loopback, sniffing an interface inside a network
namespace the test creates, and its mistaken uses. Stopped with SIGINT once its progress lines show it has
judged what was sent, so no test waits on the clock."""

from __future__ import annotations

import json
import shutil
import signal
import socket
import subprocess
import sys
from pathlib import Path

import pytest

from imc_conformance.cli import main
from imc_conformance.suites import load_suite
from imc_conformance.suites.imc import codec

DEFS = load_suite("imc").defs
HERE = Path(__file__).parent


def frame(abbrev: str, fields=None, src=30, dst=0xFFFF) -> bytes:
    header = {"timestamp": 1.0, "src": src, "src_ent": 1, "dst": dst, "dst_ent": 255}
    return codec.encode(DEFS, {"abbrev": abbrev, "header": header, "fields": fields or {}})


def free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_watch_judges_what_is_sent_to_its_socket(tmp_path):
    port = free_port()
    watch = subprocess.Popen([sys.executable, "-m", "imc_conformance.cli", "watch", f"udp://127.0.0.1:{port}",
                              "--json", str(tmp_path / "w.json")], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                             text=True)
    try:
        assert "watching udp://127.0.0.1:" in watch.stderr.readline()
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
            for _ in range(4):
                s.sendto(frame("Heartbeat"), ("127.0.0.1", port))
            s.sendto(frame("Heartbeat")[:-1] + b"\x00", ("127.0.0.1", port))
            s.sendto(b"not imc at all", ("127.0.0.1", port))
    finally:
        watch.send_signal(signal.SIGINT)  # whatever reached the socket before is judged
        out, err = watch.communicate(timeout=60)
    assert watch.returncode == 1, err
    doc = json.loads((tmp_path / "w.json").read_text())
    cases = {c["id"]: c for m in doc["messages"] for c in m["cases"]}
    assert cases["imc/Heartbeat/capture/frame/valid"]["detail"].startswith("count: 4 frames")
    assert cases["imc/Heartbeat/capture/frame/crc"]["verdict"] == "FAIL"
    assert "1 not judged: datagrams on the ports that are not frames of the suite" in doc["notes"]
    assert "Traceback" not in err


def _namespaces() -> str | None:
    if shutil.which("unshare") is None or shutil.which("ip") is None:
        return "unshare and ip (util-linux, iproute2) are needed"
    done = subprocess.run(["unshare", "-rn", "true"], capture_output=True)
    return None if done.returncode == 0 else f"cannot create a network namespace: {done.stderr.decode()[:200]}"


@pytest.mark.skipif(_namespaces() is not None, reason=str(_namespaces()))
def test_watch_sniffs_an_interface_and_sees_whole_exchanges(tmp_path):
    done = subprocess.run(["unshare", "-rn", sys.executable, str(HERE / "watch_in_namespace.py"),
                           str(tmp_path / "w.json")], capture_output=True, text=True, timeout=180)
    assert done.returncode == 1, done.stderr  # the garbage frame fails
    doc = json.loads((tmp_path / "w.json").read_text())
    cases = {c["id"]: c["verdict"] for m in doc["messages"] for c in m["cases"]}
    assert cases["imc/AcousticSystemsQuery/capture/exchange/acoustic-systems/answered"] == "PASS"
    assert cases["imc/AcousticSystemsQuery/capture/exchange/acoustic-systems/to-requester"] == "PASS"
    assert cases["imc/unidentified/capture/frame/header-truncated"] == "FAIL"
    assert doc["notes"][0].startswith("3 records")  # loopback shows each packet twice: the copy is dropped


CAP_NET_RAW = 13  # linux/capability.h


def _has_net_raw() -> bool:
    """Whether this process may sniff (CAP_NET_RAW in its effective set)."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("CapEff:"):
            return bool(int(line.split()[1], 16) >> CAP_NET_RAW & 1)
    return False


def _without_net_raw(argv: list[str]) -> list[str]:
    """``argv`` run by this very user without CAP_NET_RAW: as it is where the process lacks the capability (a
    normal user), else under setpriv with the capability dropped from the bounding and inheritable sets."""
    if not _has_net_raw():
        return argv
    if shutil.which("setpriv") is None:
        pytest.skip("this process may sniff, and setpriv (util-linux) is needed to take the privilege away")
    return ["setpriv", "--bounding-set=-net_raw", "--inh-caps=-net_raw", *argv]


def test_sniffing_without_privileges_says_so(tmp_path):
    argv = _without_net_raw([sys.executable, "-m", "imc_conformance.cli", "watch", "--iface", "lo", "--duration", "1"])
    done = subprocess.run(argv, capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert done.returncode == 2, done.stderr
    assert "sniffing needs privileges (CAP_NET_RAW" in done.stderr and done.stderr.count("\n") == 1


@pytest.mark.parametrize("argv, message", [
    ([], "give what to watch: udp://ADDR:PORT (a socket) or --iface NAME"),
    (["udp://127.0.0.1:6001", "--iface", "lo"], "give what to watch"),
    (["udp://224.0.75.69:30100"], "never joins a group"),
    (["udp://255.255.255.255:6001"], "never joins a group"),
    (["--iface", "no-such-if0"], "--iface no-such-if0: no such network interface"),
    (["--iface", "../lo"], "no such network interface"),
    (["udp://127.0.0.1:6001", "--message", "Nope"], "unknown message(s): Nope"),
    (["udp://example.invalid:6001"], "example.invalid"),
    (["udp://127.0.0.1:6001", "--port", "6002"], "--port is for --iface"),
])
def test_mistaken_watches_are_one_line(argv, message, capsys):
    assert main(["watch", *argv]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1
