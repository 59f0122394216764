"""The Iridium/SMS gateway stand-in: what a node's satellite or SMS gateway does with one message, chosen by the
message itself, so that a scenario can make the gateway fail, slow down or vanish without reaching the node's
configuration.

A message whose data holds ``imc-conformance:gateway=<mode>`` (ASCII, anywhere in its first 256 bytes) is handled in
that mode; any other in the stand-in's default mode (``ok``):

- ``ok``: delivered at once;
- ``fail``: refused: the connection is reset without an answer (every HTTP client sees an error);
- ``slow``: delivered ``slow`` seconds later (longer than any time to live the scenarios give);
- ``gone``: the gateway vanishes: this connection is reset and the stand-in stops listening for ``gone`` seconds.

``plan`` is the rule, sans-IO (the reference node's simulated gateways follow it); ``GatewayServer`` is the HTTP
stand-in a node such as DUNE is configured to post to (``imc-conformance gateway``), on loopback only. DUNE's
``Simulators.Iridium`` posts an IridiumMsgTx's data, hex-encoded, to ``Server Address:Server Port/Server Path`` and
reports OK once the exchange ends without a socket error, ERROR with the error's text otherwise.
"""

from __future__ import annotations

import binascii
import http.server
import io
import ipaddress
import socket
import struct
import threading
import time

MARK = b"imc-conformance:gateway="
MODES = ("ok", "fail", "slow", "gone")
LOOKED_AT = 256  # bytes of a message searched for the mark
MAX_BODY = 1 << 20  # bytes of a post read at most
READ_TIMEOUT = 10.0  # seconds a post may take to arrive, all of it (a client dribbling bytes gets no more)
MAX_CONNECTIONS = 32  # connections handled at once; any beyond are reset
SLOW, GONE = 30.0, 60.0  # default seconds: how late a slow gateway answers, how long a gone one stays away


def plan(data: bytes, default: str = "ok") -> str:
    """The mode a message is handled in: the one its data names, or ``default``."""
    head = bytes(data[:LOOKED_AT])
    at = head.find(MARK)
    if at < 0:
        return default
    rest = head[at + len(MARK):]
    for mode in MODES:
        if rest.startswith(mode.encode()):
            return mode
    return default


def marked(mode: str) -> str:
    """The hex of a message's data that asks the gateway for ``mode`` (what a scenario sends)."""
    if mode not in MODES:
        raise ValueError(f"unknown gateway mode {mode!r}; one of {', '.join(MODES)}")
    return (MARK + mode.encode()).hex()


def simulated(mode: str, ttl: float, states: tuple, attempt: str, expired: str, failed: str,
              broken: str | None = None) -> tuple:
    """The reference node's simulated gateway: the (delay, state, text) a request's status goes through with the
    gateway in ``mode``: ``states`` when it delivers at once; the request's first state, then a failure (``failed``)
    with its reason when the gateway refuses it (``fail``, after an ``attempt``) or cannot be reached (``gone``); when
    it is slow, the request ends ``expired`` at its time to live (``ttl``) unless the gateway answers first.
    ``broken``: the reference node's broken behaviour (breaks.py), where it touches the gateway."""
    first = states[:1]

    def text(why: str) -> str:
        return "" if broken == "error-without-text" else why

    if mode == "fail":
        return (*first, (0.2, attempt, ""), (0.3, failed, text("the gateway refused the message (connection reset)")))
    if mode == "gone":
        return (*first, (0.2, failed, text("the gateway cannot be reached")))
    if mode != "slow":
        return states
    if broken == "retries-after-ttl":
        # attempted again past the ttl and past the register's tolerance for a real link (bound "link", 3 s)
        return (*first, (0.2, attempt, ""), (ttl + 4.0, attempt, ""), (ttl + 4.5, failed, text("no answer")))
    if SLOW < ttl or broken == "sms-ignores-timeout" and attempt == "TRANSMITTING":
        return (*first, (0.2, attempt, ""), (SLOW, states[-1][1], ""))
    late = ((SLOW, states[-1][1], ""),) if broken == "late-success" and attempt == "TRANSMIT" else ()
    return (*first, (0.2, attempt, ""), (float(ttl), expired, text("no answer from the gateway in time")), *late)


def _body(raw: bytes) -> bytes:
    """A post's message data: DUNE posts it hex-encoded (Content-Type application/hub); anything else as it came."""
    text = raw.strip()
    if text and len(text) % 2 == 0:
        try:
            return binascii.unhexlify(text)
        except (binascii.Error, ValueError):
            pass
    return raw


class GatewayServer(http.server.ThreadingHTTPServer):
    """The HTTP stand-in on a loopback address: each post handled in the mode ``plan`` gives it (``default``
    otherwise); ``slow`` and ``gone``: the seconds of those modes. ``log``: called with one line per post."""

    daemon_threads = True
    request_queue_size = 16

    def __init__(self, address: tuple[str, int], default: str = "ok", slow: float = SLOW, gone: float = GONE,
                 log=None):
        host = address[0]
        try:
            loopback = ipaddress.ip_address(host).is_loopback
        except ValueError:
            loopback = False  # a name: never resolved
        if not loopback:
            raise ValueError(f"{host}: the gateway stand-in listens on a loopback address only (e.g. 127.0.0.1)")
        if default not in MODES:
            raise ValueError(f"unknown gateway mode {default!r}; one of {', '.join(MODES)}")
        self.address_family = socket.AF_INET6 if ":" in host else socket.AF_INET
        self.default, self.slow, self.gone, self.log = default, slow, gone, log or (lambda line: None)
        self.away_until = 0.0
        self.stopping = threading.Event()
        self.slots = threading.BoundedSemaphore(MAX_CONNECTIONS)
        super().__init__(address, _Post)

    def process_request(self, request, client_address) -> None:
        """A thread per connection, at most MAX_CONNECTIONS at once: any beyond are reset, not queued."""
        if not self.slots.acquire(blocking=False):
            self.log(f"{client_address[0]}: more than {MAX_CONNECTIONS} connections at once: reset")
            _reset(request)
            return
        try:
            super().process_request(request, client_address)
        except BaseException:
            self.slots.release()
            raise

    def process_request_thread(self, request, client_address) -> None:
        try:
            super().process_request_thread(request, client_address)
        finally:
            self.slots.release()

    def verify_request(self, request, client_address) -> bool:
        if time.monotonic() < self.away_until:  # gone: the connection is reset, as a closed port refuses one
            _reset(request)
            return False
        return True

    def handle_error(self, request, client_address) -> None:
        """A post that broke off (a client that went away, a reset of the stand-in's own making): one line."""
        self.log(f"{client_address[0]}: the exchange broke off")

    def stop(self) -> None:
        self.stopping.set()
        self.shutdown()
        self.server_close()


class _Deadline(io.RawIOBase):
    """A connection's reading side that gives up ``seconds`` after it began, however the bytes trickle in (the
    socket's own timeout is per read: a client sending a byte at a time would hold the connection for ever)."""

    def __init__(self, sock, seconds: float, clock=time.monotonic):
        self.sock, self.clock = sock, clock
        self.until = clock() + seconds

    def readable(self) -> bool:
        return True

    def readinto(self, buffer) -> int:
        left = self.until - self.clock()
        if left <= 0:
            raise TimeoutError("the request took longer than the stand-in waits for one")
        self.sock.settimeout(left)
        return self.sock.recv_into(buffer)


class _Post(http.server.BaseHTTPRequestHandler):
    server: GatewayServer
    timeout = READ_TIMEOUT

    def setup(self) -> None:
        super().setup()
        self.rfile.close()
        self.rfile = io.BufferedReader(_Deadline(self.connection, READ_TIMEOUT))

    def do_POST(self):  # noqa: N802 (the http.server naming)
        try:
            length = int(self.headers.get("Content-Length") or 0)
        except ValueError:
            length = -1
        if not 0 <= length <= MAX_BODY:
            self.send_error(413 if length > MAX_BODY else 400)
            return
        data = _body(self.rfile.read(length))
        mode = plan(data, self.server.default)
        self.server.log(f"{self.client_address[0]} posted {len(data)} bytes to {self.path[:80]!r}: {mode}")
        if mode == "gone":
            self.server.away_until = time.monotonic() + self.server.gone
        if mode in ("fail", "gone"):
            _reset(self.connection)
            self.close_connection = True
            return
        if mode == "slow" and self.server.stopping.wait(self.server.slow):
            return
        self.send_response(200)
        self.send_header("Content-Length", "0")
        self.end_headers()

    def log_message(self, *args):
        pass


def _reset(sock) -> None:
    """Close ``sock`` with a reset (no answer): SO_LINGER with a zero timeout."""
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
    except OSError:
        pass
    try:
        sock.close()
    except OSError:
        pass
