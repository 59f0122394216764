"""The adapter contract over a socket: an implementation that runs elsewhere (an embedded target, another
container, a vehicle's computer) serves the JSON lines of the subprocess session on TCP or a Unix socket, and the
runner connects (``--adapter-socket tcp://HOST:PORT`` or ``unix:PATH``).

Everything but the channel is the subprocess session's: pipelining, batches, bounded lines, strict JSON, replay
one request at a time after a failure so that the right case is blamed. A connection the peer closes or resets is
what a crash is for a program: the session reconnects and replays, and a request that loses the connection again
while it is alone in flight is a CRASH; a request without an answer within the timeout is a TIMEOUT, and the
connection is replaced. When no new connection can be made the remaining cases fail with that reason. The peer is
untrusted: its name is resolved once, when the session is made (each of its addresses is then tried in turn); every
line it sends is bounded and parsed as data; nothing it sends is executed or followed.
"""

from __future__ import annotations

import socket
import threading
import time
from urllib.parse import urlsplit

from ..core.session import AdapterStartError
from .channel import Channel, read_lines
from .subprocess import SubprocessSession


def parse_address(url: str) -> tuple[list[tuple[int, object]], str]:
    """The (family, address) pairs of ``tcp://HOST:PORT``, ``tcp://[IPv6]:PORT`` or ``unix:PATH``, to be tried in
    turn, and how to name it; the host name, if not a literal address, is looked up here, once (every address it
    has). ValueError for anything else."""
    if url.startswith("unix:"):
        path = url[len("unix://"):] if url.startswith("unix://") else url[len("unix:"):]
        if not path or "\0" in path:
            raise ValueError(f"--adapter-socket {url!r}: expected unix:PATH")
        return [(socket.AF_UNIX, path)], f"unix:{path}"
    try:
        parts = urlsplit(url)
        port = parts.port
    except ValueError:  # an unclosed [, a port out of range
        parts, port = None, None
    if port is None or parts.scheme != "tcp" or not parts.hostname or parts.path not in ("", "/"):
        raise ValueError(f"--adapter-socket {url!r}: expected tcp://HOST:PORT (IPv6 as tcp://[::1]:PORT) or unix:PATH")
    try:
        found = socket.getaddrinfo(parts.hostname, port, type=socket.SOCK_STREAM)
    except (socket.gaierror, UnicodeError) as exc:
        raise ValueError(f"--adapter-socket {url!r}: cannot resolve {parts.hostname!r}: {exc}") from None
    return list(dict.fromkeys((family, address) for family, _, _, _, address in found)), url


def connect(addresses: list[tuple[int, object]], timeout: float) -> socket.socket:
    """A stream socket connected to the first of ``addresses`` that accepts (each given ``timeout`` seconds); the
    last refusal if none does."""
    error = OSError("no address")
    for family, address in addresses:
        sock = socket.socket(family, socket.SOCK_STREAM)
        sock.settimeout(timeout)
        try:
            sock.connect(address)
            return sock
        except OSError as exc:
            sock.close()
            error = exc
    raise error


class _Connection(Channel):
    """One connection, with the events and operations the session expects of a program's run: ``("line",
    bytes)``, ``("oversize", ...)``, and at the connection's end ``("exit", b"")`` then ``("eof", b"")``."""

    def __init__(self, addresses: list[tuple[int, object]], max_line: int, timeout: float):
        sock = connect(addresses, timeout)
        sock.settimeout(None)
        super().__init__()
        self.sock = sock
        self.stderr_start = 0
        self._ended = threading.Event()
        threading.Thread(target=self._read, args=(sock.makefile("rb"), max_line), daemon=True).start()
        threading.Thread(target=self._write, daemon=True).start()

    def _read(self, stream, max_line: int) -> None:
        read_lines(stream, max_line, self.events, end=())
        self._ended.set()
        self.events.put(("exit", b""))
        self.events.put(("eof", b""))

    def _write(self) -> None:
        try:
            while (line := self._outbox.get()) is not None:
                self.sock.sendall(line)
        except OSError:
            pass  # the peer is gone; the reader reports it

    def exited(self) -> None:
        if self.exited_at is None:
            self.exited_at = time.monotonic()

    def exit_status(self, wait: float = 0.5) -> str | None:
        """"closed the connection" once the peer has, else None."""
        return "closed the connection" if self._ended.wait(min(wait, 0.5)) else None

    def kill_group(self) -> None:
        """Nothing to kill: the program is the peer's."""

    def stop(self, *, kill: bool = False, grace: float = 2.0) -> None:
        self._outbox.put(None)
        try:
            self.sock.shutdown(socket.SHUT_RDWR)
        except OSError:
            pass
        self.sock.close()


class SocketSession(SubprocessSession):
    """A session over a program serving the adapter contract on a socket (see the module docstring)."""

    def __init__(self, url: str, *, name: str | None = None, **settings):
        settings.pop("memory_limit", None)  # the peer's memory is the peer's
        self.addresses, shown = parse_address(url)
        super().__init__([], name=name or shown, memory_limit=0, **settings)
        self.url = shown

    def _open(self):
        try:
            return _Connection(self.addresses, self.max_line, self.hello_timeout)
        except OSError as exc:
            raise AdapterStartError(f"cannot connect to {self.url}: {exc.strerror or exc}") from exc
