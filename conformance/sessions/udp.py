"""UDP for live targets: parsing a target URL, refusing group addresses, and a bounded, timestamped transport.

Safety first: a run talks to one unicast host. Multicast and broadcast targets and binds are refused unless
explicitly allowed, because real IMC nodes (DUNE, imcpy actors) listen on 224.0.75.69 and a test run must
never reach a real vehicle by accident. Datagrams from any other host than the target's are dropped.

What the kernel drops is counted, never silent: the sockets get a large receive buffer, and the count of
datagrams the kernel dropped because the session did not read them in time (Linux: ``SO_RXQ_OVFL`` with every
datagram read, and ``/proc/net/udp`` when asked) is what ``drops`` says, so a verdict a lost datagram could
have changed is made INCONCLUSIVE rather than FAIL.
"""

from __future__ import annotations

import errno
import ipaddress
import os
import select
import socket
import struct
import sys
import time
import urllib.parse

MAX_DATAGRAM = 65535
SCHEMES = ("udp", "imc+udp")
RECEIVE_BUFFER = 8 << 20  # bytes asked for each socket's receive queue (the kernel may give less)
LINUX = sys.platform.startswith("linux")
SO_RXQ_OVFL, SO_RCVBUFFORCE = 40, 33  # linux/socket.h; Python's socket module does not name them
PROC_UDP = ("/proc/net/udp", "/proc/net/udp6")


def parse_endpoint(text: str, what: str, default_port: int | None = None) -> tuple[str, int]:
    """``udp://HOST:PORT`` or ``imc+udp://HOST:PORT/`` (IPv6 as ``[::1]``), or ``HOST:PORT`` for a bind (where
    port 0, any free port, is allowed: a target needs a real one); ValueError with a one-line reason."""
    raw = text if "://" in text else f"udp://{text}"
    try:
        url = urllib.parse.urlsplit(raw)
        host, port = url.hostname, url.port
    except ValueError as exc:
        raise ValueError(f"{what} {text!r}: {exc}") from None
    if url.scheme not in SCHEMES:
        raise ValueError(f"{what} {text!r}: the scheme must be one of {', '.join(s + '://' for s in SCHEMES)}")
    if not host:
        raise ValueError(f"{what} {text!r}: no host (expected e.g. udp://127.0.0.1:6002)")
    if url.path not in ("", "/") or url.query or url.fragment or url.username or url.password:
        raise ValueError(f"{what} {text!r}: expected only a host and a port")
    port = port if port is not None else default_port
    if port is None:
        raise ValueError(f"{what} {text!r}: no port (expected e.g. udp://127.0.0.1:6002)")
    if port == 0 and default_port is None:
        raise ValueError(f"{what} {text!r}: port 0 is no port a node listens on (expected e.g. udp://127.0.0.1:6002)")
    return host, port


def url(host: str, port: int) -> str:
    """``udp://HOST:PORT`` as ``--target`` reads it back (an IPv6 address in brackets)."""
    return f"udp://[{host}]:{port}" if ":" in host else f"udp://{host}:{port}"


def resolve(host: str, port: int, what: str) -> tuple[int, tuple]:
    """(address family, socket address) of a host given by name or number; ValueError if it does not resolve."""
    try:
        info = socket.getaddrinfo(host, port, type=socket.SOCK_DGRAM)
    except (socket.gaierror, UnicodeError) as exc:
        raise ValueError(f"{what} {host!r} does not resolve: {exc}") from None
    family, _, _, _, address = info[0]
    return family, address


def bound_socket(family: int, address: tuple, what: str) -> socket.socket:
    """A UDP socket bound to ``address``, with a large receive buffer and its drops counted (``read``); ValueError
    naming ``what`` if the bind fails."""
    sock = socket.socket(family, socket.SOCK_DGRAM)
    try:
        sock.bind(address)
    except OSError as exc:
        sock.close()
        raise ValueError(f"{what}: cannot bind {address[0]}:{address[1]}: {exc.strerror or exc}") from None
    if LINUX:
        try:  # root may pass net.core.rmem_max; anyone else gets at most that
            sock.setsockopt(socket.SOL_SOCKET, SO_RCVBUFFORCE, RECEIVE_BUFFER)
        except OSError:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, RECEIVE_BUFFER)
        try:
            sock.setsockopt(socket.SOL_SOCKET, SO_RXQ_OVFL, 1)
        except OSError:
            pass
    return sock


def read(sock: socket.socket) -> tuple[bytes, tuple, int | None]:
    """One datagram of at most 65,535 bytes, where it came from, and the socket's count of datagrams the kernel
    dropped so far (None where the kernel does not say)."""
    data, ancillary, _, source = sock.recvmsg(MAX_DATAGRAM, socket.CMSG_SPACE(4))
    for level, kind, value in ancillary:
        if level == socket.SOL_SOCKET and kind == SO_RXQ_OVFL and len(value) >= 4:
            return data, source, struct.unpack("=I", value[:4])[0]
    return data, source, None


def kernel_drops(socks) -> dict[int, int]:
    """Datagrams the kernel dropped on each socket (by file descriptor) as ``/proc/net/udp`` counts them; {}
    where it cannot be read."""
    inodes = {os.fstat(s.fileno()).st_ino: s.fileno() for s in socks}
    out = {}
    for name in PROC_UDP if LINUX else ():
        try:
            with open(name, "rb") as table:
                lines = table.read(1 << 22).splitlines()[1:]
        except OSError:
            continue
        for line in lines:
            cols = line.split()
            if len(cols) >= 13 and cols[9].isdigit() and int(cols[9]) in inodes and cols[-1].isdigit():
                out[inodes[int(cols[9])]] = int(cols[-1])
    return out


def group_address(host: str) -> str | None:
    """Why ``host`` (a numeric address) is not a unicast address, or None. (A subnet's directed broadcast address
    cannot be told from a host's without the netmask: the send then fails, and says so.)"""
    try:
        ip = ipaddress.ip_address(host.split("%")[0])
    except ValueError:
        return None
    ip = getattr(ip, "ipv4_mapped", None) or ip
    if ip.is_multicast:
        return "a multicast address"
    if ip == ipaddress.IPv4Address("255.255.255.255"):
        return "a broadcast address"
    if ip.is_unspecified:
        return "the unspecified address"
    return None


def route_source(family: int, target: tuple) -> str:
    """The local address the system would send to ``target`` from (a route lookup: nothing is sent)."""
    probe = socket.socket(family, socket.SOCK_DGRAM)
    try:
        probe.connect(target)
        return probe.getsockname()[0]
    except OSError as exc:
        raise ValueError(f"no route to {target[0]}: {exc.strerror or exc}") from None
    finally:
        probe.close()


class UdpTransport:
    """One socket, bound to ``bind``, talking to ``target``; every wait bounded, every read at most one datagram
    of at most 65,535 bytes, each timestamped on the monotonic clock on arrival. ``listen``: further ports of the
    bind host to receive on, the first free one taken (a protocol's discovery ports: a node may announce itself
    there rather than to its peers' own port); none free is no error."""

    def __init__(self, target: tuple, bind: tuple, family: int, listen=()):
        self.target, self.family = target, family
        if (":" in bind[0]) != (family == socket.AF_INET6):
            raise ValueError(f"--bind {bind[0]} and the target {target[0]} are not of the same address family")
        self.sock = bound_socket(family, bind, "--bind")
        self.sock.setblocking(False)
        self.address = self.sock.getsockname()
        self.sockets = [self.sock]
        for port in listen:
            try:
                extra = bound_socket(family, (bind[0], port), "a discovery port")
            except ValueError:
                continue
            extra.setblocking(False)
            self.sockets.append(extra)
            break
        self._drops: dict[int, int] = {}  # datagrams the kernel dropped, per socket (by file descriptor)
        self.listening = [s.getsockname()[1] for s in self.sockets[1:]]
        self.offset = time.time() - time.monotonic()
        self.dropped = 0  # datagrams from other hosts
        self.send_errors: dict[str, int] = {}  # transient send errors (the node's port closed, buffers full), by kind

    def now(self) -> float:
        return time.monotonic()

    def epoch(self, t: float) -> float:
        return self.offset + t

    def send(self, data: bytes, address=None) -> str | None:
        """Send one datagram; why it could not be sent, or None. A closed port (an earlier ICMP error) or full
        buffers are counted and not reported: the scenarios' bounds judge the silence that follows."""
        try:
            self.sock.sendto(data, self.target if address is None else address)
        except OSError as exc:
            if exc.errno in (errno.ECONNREFUSED, errno.ENOBUFS, errno.EAGAIN):
                self.send_errors[exc.strerror] = self.send_errors.get(exc.strerror, 0) + 1
                return None
            return f"cannot send {len(data)} bytes to {(address or self.target)[0]}: {exc.strerror or exc}"
        return None

    def receive(self, until: float) -> tuple[float, bytes, tuple] | None:
        while True:
            wait = until - time.monotonic()
            if wait <= 0:
                return None
            ready, _, _ = select.select(self.sockets, [], [], wait)
            if not ready:
                return None
            try:
                data, source, dropped = read(ready[0])
            except OSError:
                continue  # e.g. ICMP port unreachable reported on the socket
            if dropped is not None:
                fd = ready[0].fileno()
                self._drops[fd] = max(self._drops.get(fd, 0), dropped)
            if source[0] != self.target[0]:
                self.dropped += 1
                continue
            return time.monotonic(), data, source[:2]

    def drops(self, poll: bool = False) -> int:
        """Datagrams the kernel dropped because the session did not read them in time, so far; ``poll``: also ask
        the kernel now (else the count comes with the datagrams read)."""
        if poll:
            for fd, count in kernel_drops(self.sockets).items():
                self._drops[fd] = max(self._drops.get(fd, 0), count)
        return sum(self._drops.values())

    @property
    def notes(self) -> list[str]:
        """What a report should say about the link."""
        out = [f"{self.dropped} datagrams from hosts other than the target's were dropped"] if self.dropped else []
        out += [f"{n} datagrams could not be sent ({why})" for why, n in self.send_errors.items()]
        return out

    def close(self) -> None:
        for sock in self.sockets:
            sock.close()
