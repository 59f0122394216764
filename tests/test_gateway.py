"""The Iridium/SMS gateway stand-in: a message's data chooses what the gateway does with it (the rule the reference
node's simulated gateways follow too), and the HTTP stand-in a node such as DUNE posts to does it, on loopback only."""

from __future__ import annotations

import http.client
import threading

import pytest

from imc_conformance.cli import main
from imc_conformance.suites.imc.node.gateway import GatewayServer, marked, plan, simulated


def test_a_message_names_its_mode_and_anything_else_gets_the_default():
    for mode in ("ok", "fail", "slow", "gone"):
        assert plan(b"\x00\x01" + bytes.fromhex(marked(mode)) + b" more") == mode
    assert plan(b"c0ffee") == "ok" and plan(b"", "gone") == "gone"
    assert plan(b"imc-conformance:gateway=sideways", "fail") == "fail"
    assert plan(b"x" * 300 + bytes.fromhex(marked("fail"))) == "ok"  # only the first 256 bytes are looked at
    with pytest.raises(ValueError):
        marked("sideways")


def test_the_simulated_gateway_fails_with_a_reason_and_expires_a_slow_message_at_its_ttl():
    ok = ((0.005, "QUEUED", ""), (0.2, "TRANSMIT", ""), (0.5, "OK", ""))
    assert simulated("ok", 2, ok, "TRANSMIT", "EXPIRED", "ERROR") == ok
    fail = simulated("fail", 2, ok, "TRANSMIT", "EXPIRED", "ERROR")
    assert fail[-1][1] == "ERROR" and fail[-1][2] and "OK" not in [s for _, s, _ in fail]
    assert simulated("gone", 2, ok, "TRANSMIT", "EXPIRED", "ERROR")[-1][1:] == ("ERROR", "the gateway cannot be reached")
    slow = simulated("slow", 2, ok, "TRANSMIT", "EXPIRED", "ERROR")
    assert slow[-1][:2] == (2.0, "EXPIRED") and max(d for d, s, _ in slow if s == "TRANSMIT") <= 2
    assert simulated("slow", 2, ok, "TRANSMIT", "EXPIRED", "ERROR", "error-without-text")[-1][2] == ""


@pytest.fixture()
def gateway():
    lines = []
    server = GatewayServer(("127.0.0.1", 0), slow=0.0, log=lines.append)
    thread = threading.Thread(target=server.serve_forever, kwargs={"poll_interval": 0.05}, daemon=True)
    thread.start()
    yield server, lines
    server.stop()
    thread.join(5)


def _post(server, data: bytes, headers=None):
    connection = http.client.HTTPConnection(*server.server_address[:2], timeout=5)
    try:
        connection.request("POST", "/api/v1/iridium", body=data.hex(),
                           headers=headers or {"Content-Type": "application/hub"})
        return connection.getresponse().status
    except (ConnectionError, http.client.HTTPException) as exc:
        return type(exc).__name__
    finally:
        connection.close()


def test_the_stand_in_delivers_refuses_answers_late_and_vanishes_as_the_message_asks(gateway):
    server, lines = gateway
    assert _post(server, b"hello") == 200
    assert _post(server, bytes.fromhex(marked("slow"))) == 200  # late by --slow (0 s here)
    assert _post(server, bytes.fromhex(marked("fail"))) in ("ConnectionResetError", "RemoteDisconnected")
    assert _post(server, b"hello") == 200  # a refusal is for that message only
    assert _post(server, bytes.fromhex(marked("gone"))) in ("ConnectionResetError", "RemoteDisconnected")
    assert _post(server, b"hello") in ("ConnectionResetError", "RemoteDisconnected")  # gone for --gone seconds
    assert [line.rsplit(": ", 1)[1] for line in lines if "posted" in line] == ["ok", "slow", "fail", "ok", "gone"]


def test_the_stand_in_bounds_what_it_reads(gateway):
    server, _ = gateway
    connection = http.client.HTTPConnection(*server.server_address[:2], timeout=5)
    connection.putrequest("POST", "/")
    connection.putheader("Content-Length", str(1 << 30))
    connection.endheaders()
    assert connection.getresponse().status == 413
    connection.close()
    assert _post(server, b"x", headers={"Content-Length": "many"}) == 400


def test_the_stand_in_listens_on_loopback_only(capsys):
    with pytest.raises(ValueError, match="loopback"):
        GatewayServer(("0.0.0.0", 0))
    assert main(["gateway", "--host", "0.0.0.0", "--port", "0"]) == 2
    assert main(["gateway", "--host", "localhost", "--port", "0"]) == 2  # a name is never resolved
    err = capsys.readouterr().err
    assert "loopback" in err and "Traceback" not in err


def test_a_node_whose_gateway_succeeds_whatever_happens_is_caught_on_sms_too(suite, cases):
    from live_harness import run_virtual

    result, _ = run_virtual(suite, cases, broken="ok-when-gateway-fails", kinds=("scenario",))
    verdicts = {c.id: c.verdict.value for c in result.cases}
    assert verdicts["imc/SmsTx/scenario/gateway-fails"] == "NON_STRICT"
    assert verdicts["imc/IridiumMsgTx/scenario/gateway-gone"] == "NON_STRICT"
    result, _ = run_virtual(suite, cases, broken="error-without-text", kinds=("scenario",))
    assert {c.id: c.verdict.value for c in result.cases}["imc/SmsTx/scenario/gateway-fails"] == "NON_STRICT"


def test_a_request_that_trickles_in_is_cut_at_its_deadline_whatever_each_read_takes():
    """A client sending a byte at a time resets a socket's own timeout at every byte: the stand-in's deadline is
    for the whole request (a clock the test moves, no waiting)."""
    import socket

    from imc_conformance.suites.imc.node.gateway import _Deadline

    now = [0.0]
    ours, theirs = socket.socketpair()
    with ours, theirs:
        reader = _Deadline(ours, 10.0, clock=lambda: now[0])
        buffer = bytearray(4)
        theirs.sendall(b"P")
        assert reader.readinto(buffer) == 1
        now[0] = 9.0
        theirs.sendall(b"O")
        assert reader.readinto(buffer) == 1 and ours.gettimeout() == pytest.approx(1.0)
        now[0] = 10.0
        theirs.sendall(b"S")
        with pytest.raises(TimeoutError):
            reader.readinto(buffer)


def test_connections_beyond_the_limit_are_reset_not_given_a_thread_each(monkeypatch):
    import socket

    from imc_conformance.suites.imc.node import gateway as module

    monkeypatch.setattr(module, "MAX_CONNECTIONS", 2)
    lines = []
    server = GatewayServer(("127.0.0.1", 0), log=lines.append)
    thread = threading.Thread(target=server.serve_forever, kwargs={"poll_interval": 0.05}, daemon=True)
    thread.start()
    held = [socket.create_connection(server.server_address[:2], timeout=5) for _ in range(2)]
    try:
        try:  # the reset may reach the client while it still connects, or on its first read
            extra = socket.create_connection(server.server_address[:2], timeout=5)
        except ConnectionResetError:
            extra = None
        if extra is not None:
            with extra:
                try:
                    assert extra.recv(1) == b""
                except ConnectionResetError:
                    pass
        assert any("more than 2 connections" in line for line in lines)
    finally:
        for sock in held:
            sock.close()
        server.stop()
        thread.join(5)
