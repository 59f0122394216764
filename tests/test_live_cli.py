"""The live side of the command line: every mistaken option gets a one-line error (exit 2), a silent target makes
the run inconclusive (exit 2), --dry-run sends nothing, and, as a smoke test over real loopback UDP (the engine
itself is tested on virtual time), ``serve`` and ``run --target`` agree."""

from __future__ import annotations

import json
import os
import re
import signal
import socket
import subprocess
import sys

import pytest

from imc_conformance.cli import main
from imc_conformance.restart import restart_argv, restarter

PARAMS = ["--param", "peer=imc-peer-1", "--param", "beacon=b1", "--param", "sms_number=+351000000000",
          "--param", "remote_system=8208"]


@pytest.fixture
def quiet_port():
    """A loopback UDP port with a socket that never answers."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("127.0.0.1", 0))
    yield sock.getsockname()[1]
    sock.close()


@pytest.fixture
def node():
    """``imc-conformance serve`` on a free loopback port, stopped (and waited for) at the end."""
    proc = subprocess.Popen([sys.executable, "-m", "imc_conformance.cli", "serve", "--port", "0"],
                            stderr=subprocess.PIPE, text=True, start_new_session=True)
    line = proc.stderr.readline()
    port = re.search(r"udp://127\.0\.0\.1:(\d+)", line)
    assert port, line
    yield int(port[1])
    proc.send_signal(signal.SIGINT)
    try:
        assert proc.wait(timeout=10) == 0
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
        proc.stderr.close()


@pytest.mark.parametrize("args, says", [
    (["--target", "udp://224.0.75.69:6002"], "a multicast address"),
    (["--target", "udp://255.255.255.255:6002"], "a broadcast address"),
    (["--target", "udp://127.0.0.1"], "no port"),
    (["--target", "http://127.0.0.1:6002"], "the scheme must be one of"),
    (["--target", "udp://127.0.0.1:99999"], "Port out of range"),
    (["--target", "udp://no-such-host.invalid:6002"], "does not resolve"),
    (["--target", "udp://127.0.0.1:6002", "--bind", "224.0.0.1:0"], "a multicast address"),
    (["--target", "udp://127.0.0.1:6002", "--param", "nope=1"], "--param 'nope=1'"),
    (["--target", "udp://127.0.0.1:6002", "--param", "remote_system=abc"], "is an integer"),
    (["--target", "udp://127.0.0.1:6002", "--profile", "nope"], "unknown profile 'nope'"),
    (["--target", "udp://127.0.0.1:6002", "--allow-effects", "bogus"], "--allow-effects 'bogus'"),
    (["--target", "udp://127.0.0.1:6002", "--robustness", "--restart-cmd", ""], "--restart-cmd is empty"),
    (["--target", "udp://127.0.0.1:6002", "--robustness", "--restart-cmd", "'unbalanced"], "--restart-cmd cannot be split"),
    (["--target", "udp://127.0.0.1:6002", "--restart-cmd", "restart-node"], "give --robustness too"),
    (["--robustness"], "is for a live target"),
    (["--target", "udp://127.0.0.1:6002", "--src", "0x10", "--dst", "0x10"], "needs an id of its own"),
    (["--target", "udp://[::ffff:224.0.75.69]:6002"], "a multicast address"),
    (["--target", "udp://127.0.0.1:6002", "--bind", "[::1]:0"], "not of the same address family"),
    (["--target", "udp://127.0.0.1:6002", "--adapter", "imcpy"], "not both"),
    (["--suite", "ros_acomms", "--target", "udp://127.0.0.1:6002"], "has no live targets"),
    (["--suite", "ros_acomms", "--robustness"], "the suite 'ros_acomms' has no robustness phase"),
])
def test_mistaken_live_options_are_one_line_usage_errors(args, says, capsys):
    code = main(["run", "--no-progress", *args])
    err = capsys.readouterr().err
    assert code == 2 and says in err and len(err.strip().splitlines()) == 1, err


def test_a_port_in_use_is_a_one_line_error(quiet_port, capsys):
    assert main(["run", "--target", "udp://127.0.0.1:6002", "--bind", f"127.0.0.1:{quiet_port}"]) == 2
    assert "Address already in use" in capsys.readouterr().err
    assert main(["serve", "--port", str(quiet_port)]) == 2
    assert "cannot listen on" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["serve", "--port", "70000"])
    assert "a port is 0 to 65535" in capsys.readouterr().err


def test_claims_files_are_checked(tmp_path, capsys):
    bad = tmp_path / "claims.json"
    for text, says in (("{", "not JSON"), ('{"services": ["telepathy"]}', "unknown service 'telepathy'"),
                       ('["acoustic"]', 'expected {"services"'), ('{"services": [["acoustic"]]}', 'expected {"services"'),
                       ('{"capabilities": {"acoustic-request": "mostly"}}', "is not one of any, self, none"),
                       ('{"capabilities": {"acoustic-request": "self", "acoustic-request": "any"}}',
                        "the key 'acoustic-request' is given twice in one object")):
        bad.write_text(text)
        assert main(["run", "--target", "udp://127.0.0.1:6002", "--claims", str(bad)]) == 2
        err = capsys.readouterr().err
        assert says in err and err.count("\n") == 1, err


def test_serve_refuses_an_unknown_capability_in_one_line(capsys):
    assert main(["serve", "--port", "0", "--only-to-itself", "telepathy"]) == 2
    err = capsys.readouterr().err
    assert "--only-to-itself 'telepathy': one of acoustic-operation, acoustic-request" in err and err.count("\n") == 1


def test_a_silent_target_is_inconclusive_and_exits_2(quiet_port, tmp_path, capsys):
    path = tmp_path / "r.json"
    code = main(["run", "--no-progress", "--target", f"udp://127.0.0.1:{quiet_port}", "--startup", "0.3",
                 "--message", "LblConfig", "--json", str(path)])
    out = capsys.readouterr().out
    doc = json.loads(path.read_text())
    assert code == 2 and doc["exit_code"] == 2 and set(doc["summary"]) == {"INCONCLUSIVE"}
    assert "no valid frame from IMC node" in out


def test_dry_run_prints_what_would_be_sent_and_sends_nothing(capsys):
    listener = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    listener.bind(("127.0.0.1", 0))
    listener.settimeout(0.2)
    port = listener.getsockname()[1]
    try:
        assert main(["run", "--target", f"udp://127.0.0.1:{port}", "--dry-run", "--robustness", "--allow-effects",
                     *PARAMS, "--message", "AcousticRequest", "--message", "Heartbeat"]) == 0
        with pytest.raises(TimeoutError):
            listener.recvfrom(65535)
    finally:
        listener.close()
    out = capsys.readouterr().out
    assert "imc/AcousticRequest/scenario/range request:" in out and '"type": "RANGE"' in out
    assert "the robustness phase:" in out and "imc/Heartbeat/robustness/still-served: sends nothing; waits for: alive" in out


def test_list_scenarios_names_what_they_need(capsys):
    assert main(["list", "--scenarios"]) == 0
    out = capsys.readouterr().out
    assert "imc/AcousticRequest/scenario/range\tneeds: peer\teffects: transmits-acoustically\tcapability: acoustic-request" in out
    assert "#   peer: a system the node reaches acoustically" in out
    assert "#   acoustic-request (service acoustic): AcousticRequest answered with AcousticStatus" in out
    assert main(["list", "--scenarios", "--suite", "ros_acomms"]) == 0
    assert "ros_acomms/PingModemRequest/scenario/reply\tneeds: ping_dest" in capsys.readouterr().out


def test_the_restart_command_runs_without_a_shell_and_says_why_it_failed(tmp_path):
    assert restarter([sys.executable, "-c", "pass"])() is None
    failed = restarter([sys.executable, "-c", "import sys; sys.stderr.write('no node here'); sys.exit(3)"])()
    assert failed == "the restart command exited with 3: no node here"
    assert "could not run" in restarter([str(tmp_path / "missing")])()
    assert restart_argv(f"{sys.executable} --fast 'a b'") == [sys.executable, "--fast", "a b"]


@pytest.mark.parametrize("command, why", [
    ("/nonexistent/restart", "/nonexistent/restart is not a program that can be run"),
    ("no-such-restart-program --fast", "no-such-restart-program is not a program that can be run (not found on PATH)"),
    ("", "--restart-cmd is empty"),
])
def test_a_restart_command_that_cannot_run_is_refused_before_the_run(command, why, capsys):
    code = main(["run", "--target", "udp://127.0.0.1:9", "--robustness", "--restart-cmd", command, "--no-progress"])
    err = capsys.readouterr().err
    assert code == 2 and why in err and err.count("\n") == 1, err


def test_a_restart_command_that_leaves_the_node_in_the_background_counts_by_its_exit(tmp_path):
    """Item 5 of the second hardening round: the node the command starts holds its output; the command's exit is
    what counts (the node is still running when the restart is over)."""
    script = tmp_path / "restart.sh"
    script.write_text(f"#!/bin/sh\n{sys.executable} -c 'import time; time.sleep(600)' &\necho $! > {tmp_path / 'pid'}\n"
                      "echo started >&2\n")
    script.chmod(0o755)
    assert restarter(restart_argv(str(script)))() is None
    pid = int((tmp_path / "pid").read_text())
    try:
        os.kill(pid, 0)  # the backgrounded node outlived the restart: it was not waited for
    finally:
        os.kill(pid, signal.SIGKILL)


def test_serve_and_run_agree_over_loopback(node, tmp_path, capsys):
    path = tmp_path / "r.json"
    code = main(["run", "--no-progress", "--target", f"udp://127.0.0.1:{node}", "--allow-effects", *PARAMS,
                 "--message", "AcousticSystemsQuery", "--message", "LblConfig", "--message", "HistoricDataQuery",
                 "--time-scale", "2", "--json", str(path)])
    doc = json.loads(path.read_text())
    assert code == 0, capsys.readouterr().out
    assert set(doc["summary"]) <= {"PASS", "IMPL_DEFINED", "UNSUPPORTED"} and doc["summary"]["PASS"] >= 15  # readings
    unclaimed = [c for m in doc["messages"] for c in m["cases"] if c["verdict"] == "UNSUPPORTED"]
    assert all("judged only where --claims claims it" in c["detail"] for c in unclaimed)  # LBL navigation, unclaimed
    assert "profile: seed" in doc["notes"] and any(n.startswith("parameters: peer=imc-peer-1") for n in doc["notes"])


def test_the_ros_reference_handler_runs_from_the_command_line(capsys):
    code = main(["run", "--no-progress", "--suite", "ros_acomms", "--adapter", "reference-handler", "--allow-effects",
                 "--param", "ping_dest=2", "--param", "silent_dest=127"])
    out = capsys.readouterr().out
    assert code == 0 and re.search(r"\d+ cases in [\d.]+ s: \d+ PASS\n", out), out[-500:]
