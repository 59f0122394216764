"""The adapter contract over a socket (``--adapter-socket``): the same verdicts as the subprocess session, and the
same blame when the peer misbehaves.

A test server listens on loopback TCP or a Unix socket and serves each connection with a fresh run of the hostile
adapter (``tests/hostile_adapter.py``), its stdin and stdout being the connection: a crash of the program drops
the connection, a hang leaves it silent, garbage arrives as lines, as they would from a remote implementation.
"""

from __future__ import annotations

import socket
import subprocess
import sys
import threading
from contextlib import contextmanager
from pathlib import Path

import pytest

from harness import verdicts as run_verdicts

from imc_conformance.cli import main as cli_main
from imc_conformance.core.session import AdapterStartError
from imc_conformance.core.verdicts import Verdict
from imc_conformance.files import open_corpus
from imc_conformance.sessions.stream_socket import SocketSession, parse_address

EDITION = "imc-5.4.30"
HOSTILE = Path(__file__).resolve().parent / "hostile_adapter.py"
SUITE, CASES = open_corpus("imc")
SELECTION = [c for c in CASES if c.group in ("LblRange", "AcousticStatus")]
TRIGGER = "imc/LblRange/realistic/crosscheck"
TRIGGER_FRAME = next(c for c in SELECTION if c.id == TRIGGER).data["frames"]["le"]


class Server:
    """Serves each accepted connection with a new run of the hostile adapter in ``mode``; ``accept_once``: the
    listener closes after its first connection (the implementation went away)."""

    def __init__(self, family: int, address, mode: str, accept_once: bool = False):
        self.listener = socket.socket(family, socket.SOCK_STREAM)
        self.listener.bind(address)
        self.listener.listen(8)
        self.mode, self.accept_once, self.children, self.connections = mode, accept_once, [], 0
        name = self.listener.getsockname()
        self.url = f"unix:{name}" if family == socket.AF_UNIX else f"tcp://{name[0]}:{name[1]}"
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self) -> None:
        while True:
            try:
                conn, _ = self.listener.accept()
            except OSError:
                return
            self.connections += 1  # counted before the program can answer: no race with the session
            with conn:
                self.children.append(subprocess.Popen([sys.executable, str(HOSTILE), self.mode, TRIGGER_FRAME],
                                                      stdin=conn.fileno(), stdout=conn.fileno(),
                                                      stderr=subprocess.DEVNULL))
            if self.accept_once:
                self.listener.close()
                return

    def close(self) -> None:
        self.listener.close()
        for child in self.children:
            child.kill()
            child.wait()


@contextmanager
def served(mode: str, where: str = "tcp", tmp_path: Path | None = None, **options):
    """(server, session) for the hostile adapter in ``mode`` on loopback TCP or a Unix socket. The timeout is short
    only where the program hangs (its TIMEOUT is what is tested): elsewhere a loaded machine must not turn a slow
    answer (a 50 MB line takes a while to write) into a TIMEOUT."""
    if where == "tcp":
        server = Server(socket.AF_INET, ("127.0.0.1", 0), mode, **options)
    else:
        server = Server(socket.AF_UNIX, str(tmp_path / "adapter.sock"), mode, **options)
    session = SocketSession(server.url, encoding_param="byte_order", timeout=1 if mode == "hang" else 30,
                            hello_timeout=30)
    try:
        yield server, session
    finally:
        session.close()
        server.close()


def verdicts(session, cases=SELECTION) -> dict[str, Verdict]:
    return {cid: v for cid, (v, _) in run_verdicts(session, cases, EDITION).items()}


@pytest.fixture(scope="module")
def reference() -> dict[str, Verdict]:
    with served("reference") as (_, session):
        return verdicts(session)


def test_the_reference_program_passes_over_tcp(reference):
    assert set(reference.values()) <= {Verdict.PASS, Verdict.IMPL_DEFINED}
    assert reference[TRIGGER] == Verdict.PASS


def test_a_unix_socket_gives_the_same_verdicts(reference, tmp_path):
    with served("reference", "unix", tmp_path) as (_, session):
        assert session.hello()["implementation"] == "hostile reference codec"
        assert verdicts(session) == reference


@pytest.mark.parametrize("mode, verdict, reconnects", [
    ("crash", Verdict.CRASH, True),  # the program dies: the connection drops
    ("hang", Verdict.TIMEOUT, True),
    ("garbage", Verdict.ADAPTER_ERROR, True),
    ("unknown-id", Verdict.ADAPTER_ERROR, True),
    ("huge-line", Verdict.ADAPTER_ERROR, True),
    ("malformed", Verdict.ADAPTER_ERROR, False),  # a well-framed answer of its request: no reason to reconnect
    ("liar", Verdict.FAIL, False),
])
def test_a_misbehaving_peer_fails_only_the_case_that_triggers_it(reference, mode, verdict, reconnects):
    with served(mode) as (server, session):
        assert verdicts(session) == {**reference, TRIGGER: verdict}
        assert (server.connections > 1) == reconnects


def test_a_dropped_connection_is_named_in_the_reason():
    with served("crash") as (_, session):
        _, results = run_verdicts(session, [c for c in SELECTION if c.id == TRIGGER], EDITION)[TRIGGER]
    assert any(r.detail == "adapter closed the connection" for r in results)


def test_a_peer_that_goes_away_ends_the_run_with_a_clear_message():
    with served("crash", accept_once=True) as (server, session):
        session.hello()
        got = run_verdicts(session, SELECTION, EDITION)
    assert got[TRIGGER][0] == Verdict.ADAPTER_ERROR
    reasons = {r.detail for _, results in got.values() for r in results if r.verdict == Verdict.ADAPTER_ERROR}
    assert any(reason.startswith(f"adapter could not be restarted: cannot connect to {server.url}")
               for reason in reasons)


def test_nothing_listening_is_a_start_error():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]  # bound, never listening: connections are refused
        session = SocketSession(f"tcp://127.0.0.1:{port}", encoding_param="byte_order", hello_timeout=5)
        with pytest.raises(AdapterStartError, match=f"cannot connect to tcp://127.0.0.1:{port}"):
            session.hello()


@pytest.mark.parametrize("url", ["udp://127.0.0.1:5", "tcp://127.0.0.1", "tcp://127.0.0.1:99999", "unix:",
                                 "tcp://[::1:5", "127.0.0.1:5", "tcp://127.0.0.1:5/path"])
def test_an_address_that_is_not_one_is_refused(url):
    with pytest.raises(ValueError, match="--adapter-socket"):
        parse_address(url)


def test_ipv6_and_unix_addresses_parse():
    assert parse_address("tcp://[::1]:6000")[0][0][0] == socket.AF_INET6
    assert parse_address("unix:/run/imc.sock") == ([(socket.AF_UNIX, "/run/imc.sock")], "unix:/run/imc.sock")


@pytest.mark.parametrize("argv, message", [
    (["--adapter-socket", "tcp://127.0.0.1"], "expected tcp://HOST:PORT"),
    (["--adapter", "imcpy", "--adapter-socket", "tcp://127.0.0.1:5"], "give one of --adapter, --adapter-socket"),
    (["--adapter-socket", "tcp://127.0.0.1:5", "--target", "udp://127.0.0.1:6002"], "give either --target"),
])
def test_the_command_line_says_what_is_wrong_in_one_line(argv, message, capsys):
    assert cli_main(["run", "--message", "LblRange", "--no-progress", *argv]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and "\n" not in err and "Traceback" not in err


def test_the_command_line_runs_over_a_socket(capsys):
    with served("reference") as (server, _):
        code = cli_main(["run", "--message", "LblRange", "--no-progress", "--adapter-socket", server.url])
    assert code == 0
    assert "PASS" in capsys.readouterr().out


def test_a_name_with_several_addresses_is_tried_at_each_in_turn(reference, monkeypatch):
    """A name that resolves to ::1 first (where nothing listens) and to 127.0.0.1 (where the peer is) reaches the
    peer: every address the name has is tried, in the resolver's order."""
    server = Server(socket.AF_INET, ("127.0.0.1", 0), "reference")
    port = server.listener.getsockname()[1]
    real = socket.getaddrinfo

    def resolve(host, *args, **kwargs):
        if host != "peer.test":
            return real(host, *args, **kwargs)
        return [(socket.AF_INET6, socket.SOCK_STREAM, 6, "", ("::1", port, 0, 0)),
                (socket.AF_INET, socket.SOCK_STREAM, 6, "", ("127.0.0.1", port))]

    monkeypatch.setattr(socket, "getaddrinfo", resolve)
    session = SocketSession(f"tcp://peer.test:{port}", encoding_param="byte_order", timeout=1, hello_timeout=30)
    try:
        assert verdicts(session) == reference
    finally:
        session.close()
        server.close()
