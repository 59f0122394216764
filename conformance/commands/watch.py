"""``imc-conformance watch``: judge live traffic as it passes, frame by frame and exchange by exchange, and send
nothing. ``udp://ADDR:PORT`` judges what is sent to that socket (never joining a group); ``--iface NAME``
sniffs an interface (scapy) and so sees whole exchanges. Reports on Ctrl-C or after ``--duration``."""

from __future__ import annotations

import datetime as dt
import select
import signal
import socket
import struct
import sys
import time
from pathlib import Path

from ..errors import UsageError
from ..arguments import address, positive_seconds
from .options import add_judging, add_reports

REFRESH = 1.0  # seconds between redraws of the table
SOL_PACKET, PACKET_STATISTICS = 263, 6  # linux/socket.h, linux/if_packet.h


def add(sub) -> None:
    watch = sub.add_parser("watch", help="judge live traffic as it passes (sends nothing): udp://ADDR:PORT or --iface")
    watch.add_argument("source", nargs="?", metavar="udp://ADDR:PORT",
                       help="judge what is sent to this socket (unicast; the socket is bound, no group is joined)")
    watch.add_argument("--iface", metavar="NAME", help="sniff this interface instead (needs CAP_NET_RAW, e.g. root)")
    add_judging(watch)
    watch.add_argument("--host", type=address, metavar="ADDR|ID", help="only datagrams from or to this address or id")
    watch.add_argument("--duration", type=positive_seconds, metavar="SECONDS", help="stop after this long (default: Ctrl-C)")
    add_reports(watch)
    watch.set_defaults(func=command)


def command(args) -> int:
    from ..capture.judge import CaptureJudge, Selection
    from ..capture.records import Record
    from ..render.terminal import print_result
    from .output import report_targets, terminal, write_reports
    from .pcap import capture_rules
    from .provenance import provenance

    targets = report_targets(args)
    if (args.source is None) == (args.iface is None):
        raise UsageError("give what to watch: udp://ADDR:PORT (a socket) or --iface NAME (an interface), one of them")
    if args.source and args.port:
        raise UsageError("--port is for --iface: what is sent to the watched socket is judged whatever its port")
    suite, rules, edition = capture_rules(args)
    selection = Selection(frozenset(args.port) or None, frozenset(args.message), host=args.host,
                          listed=args.list_frames, scale=args.time_scale)
    listen = open_socket(args.source) if args.source else open_sniffer(args.iface)
    if args.source:  # everything sent to the watched socket is judged, whatever its port
        selection.ports = frozenset([listen.address[1]])
    judge = CaptureJudge(suite.name, rules, edition, selection)
    if args.source:
        host, port = listen.address[:2]
        what = f"udp://{f'[{host}]' if ':' in host else host}:{port}"  # the port bound, where 0 was asked
    else:
        what = f"interface {args.iface}"
    started = dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds")
    began = time.monotonic()
    end = began + args.duration if args.duration else float("inf")
    console = terminal()
    def judge_all(items) -> None:
        for item in items:
            if isinstance(item, Record):
                judge.feed(item)
            else:
                judge.received(item)

    stopping: list[int] = []  # Ctrl-C or SIGTERM: finish the datagrams in hand, then stop
    handlers = {sig: signal.signal(sig, lambda signum, frame: stopping.append(signum))
                for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        with _table(console, judge) as redraw:
            print(f"imc-conformance: watching {what} (Ctrl-C to stop)", file=sys.stderr, flush=True)
            while not stopping and time.monotonic() < end:
                judge_all(listen.take(min(REFRESH, end - time.monotonic())))
                report_losses(listen, judge)
                redraw()
    finally:
        for sig, handler in handlers.items():
            signal.signal(sig, handler)
        judge_all(listen.stop())  # what arrived before the stop is judged too
        report_losses(listen, judge)
    result = judge.result(implementation=what, started=started, duration=round(time.monotonic() - began, 3),
                          strict=args.strict, title=suite.title, until=time.time())
    result.provenance = provenance(args, suite, {"message": args.message, "port": args.port, "host": args.host})
    print_result(result, console)
    return 2 if write_reports(result, targets, console) else result.exit_code()


def report_losses(listen, judge) -> None:
    """Tell the judge of datagrams the listener lost since it last said (and when)."""
    lost = listen.drops() - judge.lost
    if lost > 0:
        judge.losses(listen.since, time.time(), lost)
    listen.since = time.time()


def _table(console, judge):
    """A live per-message table (rich) on a terminal; elsewhere, nothing until the end."""
    from contextlib import contextmanager

    from rich.live import Live
    from rich.table import Table

    def table():
        t = Table(title=f"{judge.records:,} records, {judge.datagrams:,} datagrams judged")
        for column in ("message", "valid", "invalid", "exchange failures"):
            t.add_column(column, justify="left" if column == "message" else "right")
        for group, valid, invalid, exchange in judge.standing():
            t.add_row(group, f"{valid:,}", f"{invalid:,}", f"{exchange:,}")
        return t

    @contextmanager
    def live():
        if not console.is_terminal:  # a log: a line whenever more was judged
            shown = [0]

            def line():
                if judge.records != shown[0]:
                    shown[0] = judge.records
                    print(f"imc-conformance: {judge.records:,} records, {judge.datagrams:,} datagrams judged",
                          file=sys.stderr, flush=True)
            yield line
            return
        with Live(table(), console=console, refresh_per_second=2, transient=True) as view:
            yield lambda: view.update(table())

    return live()


class SocketListener:
    """A UDP socket bound to the watched address: every datagram sent to it, with its sender, and the count of
    those the kernel dropped before they were read (``drops``)."""

    def __init__(self, sock: socket.socket):
        self.sock, self.address, self.number = sock, sock.getsockname(), 0
        self.dropped, self.since = 0, time.time()

    def take(self, wait: float) -> list:
        """What arrived within ``wait`` seconds (at most a thousand datagrams at a time)."""
        from ..capture.datagrams import Datagram
        from ..sessions.udp import read

        out = []
        ready, _, _ = select.select([self.sock], [], [], max(0.0, wait))
        while ready and len(out) < 1000:
            try:
                data, source, dropped = read(self.sock)
            except OSError:  # nothing more, or an ICMP error reported on the socket
                break
            self.dropped = max(self.dropped, dropped or 0)
            self.number += 1
            out.append(Datagram(self.number, time.time(), source[0], source[1], self.address[0], self.address[1], data))
        return out

    def drops(self) -> int:
        from ..sessions.udp import kernel_drops

        if not self.sock._closed:
            self.dropped = max(self.dropped, kernel_drops([self.sock]).get(self.sock.fileno(), 0))
        return self.dropped

    def stop(self) -> list:
        """Stop listening; what was already queued on the socket."""
        out, more = [], self.take(0)
        while more:
            out, more = out + more, self.take(0)
        self.drops()
        self.sock.close()
        return out


def open_socket(url: str) -> SocketListener:
    from ..sessions.udp import bound_socket, group_address, parse_endpoint, resolve

    try:
        host, port = parse_endpoint(url, "watch")
        family, address = resolve(host, port, "watch")
    except ValueError as exc:
        raise UsageError(str(exc)) from exc
    why = group_address(address[0])
    if why and why != "the unspecified address":  # 0.0.0.0 or :: binds the port on every local address: allowed
        raise UsageError(f"watch {url}: {why}; watch binds a port of this host and never joins a group "
                         "(--iface sees all the traffic of an interface)")
    try:
        sock = bound_socket(family, address, f"watch {url}")
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    sock.setblocking(False)
    return SocketListener(sock)


class Sniffer:
    """scapy's sniffer on an interface, its packets handed over as records. On loopback a packet socket sees
    every packet twice (leaving and arriving): the second, identical copy is dropped."""

    def __init__(self, iface: str, linktype: int):
        import logging
        from queue import SimpleQueue

        from scapy.sendrecv import AsyncSniffer

        logging.getLogger("scapy.runtime").setLevel(logging.ERROR)  # its guess at the loopback's link layer
        self.linktype, self.loopback = linktype, iface == "lo" or Path(f"/sys/class/net/{iface}/type").read_text(
            ).strip() == "772"
        from scapy.config import conf

        self.queue: SimpleQueue = SimpleQueue()
        self.number, self.previous = 0, None
        self.dropped, self.since = 0, time.time()
        self.socket = conf.L2listen(iface=iface)  # no BPF filter: it needs tcpdump
        self.sniffer = AsyncSniffer(opened_socket=self.socket, store=False, prn=self.queue.put)
        self.sniffer.start()
        deadline = time.monotonic() + 10  # until its socket is open (scapy sets continue_sniff then)
        while not getattr(self.sniffer, "continue_sniff", False) and self.sniffer.thread.is_alive():
            if time.monotonic() > deadline:
                raise OSError("the sniffer did not start within 10 s")
            time.sleep(0.01)
        problem = getattr(self.sniffer, "exception", None)
        if problem is not None:
            raise problem
        if not self.sniffer.thread.is_alive():
            raise OSError("the sniffer stopped at once")

    def take(self, wait: float) -> list:
        from queue import Empty

        from ..capture.records import Record

        out = []
        until = time.monotonic() + wait
        while True:
            try:
                packet = self.queue.get(timeout=max(0.0, until - time.monotonic()))
            except Empty:
                return out
            data = bytes(packet)
            if self.loopback and data == self.previous:
                self.previous = None
                continue
            self.previous = data
            self.number += 1
            out.append(Record(self.number, float(packet.time), self.linktype, data, len(data)))
            if self.queue.empty():
                return out

    def drops(self) -> int:
        """Packets the kernel dropped before the sniffer read them (PACKET_STATISTICS, which resets when read)."""
        try:
            _, dropped = struct.unpack("=II", self.socket.ins.getsockopt(SOL_PACKET, PACKET_STATISTICS, 8))
        except (OSError, AttributeError, struct.error):
            return self.dropped
        self.dropped += dropped
        return self.dropped

    def stop(self) -> list:
        """Stop sniffing; what was already captured."""
        self.drops()
        try:
            self.sniffer.stop()
        except Exception:  # noqa: BLE001 - a sniffer that never started has nothing to stop
            pass
        out, more = [], self.take(0)
        while more:
            out, more = out + more, self.take(0)
        return out


def open_sniffer(iface: str) -> Sniffer:

    from ..capture.datagrams import ETHERNET, RAW

    arphrd = {1: ETHERNET, 772: ETHERNET, 65534: RAW}  # Linux interface types: Ethernet, loopback, none (tun)
    kind = Path(f"/sys/class/net/{iface}/type")
    if "/" in iface or not kind.exists():
        raise UsageError(f"--iface {iface}: no such network interface")
    linktype = arphrd.get(int(kind.read_text().strip() or -1))
    if linktype is None:
        raise UsageError(f"--iface {iface}: its link layer (Linux type {kind.read_text().strip()}) is not Ethernet, "
                         "loopback or raw IP")
    try:
        return Sniffer(iface, linktype)
    except PermissionError:
        raise UsageError(f"--iface {iface}: sniffing needs privileges (CAP_NET_RAW: run as root or grant the "
                         "capability); udp://ADDR:PORT watches a socket without them") from None
    except OSError as exc:
        raise UsageError(f"--iface {iface}: cannot sniff: {exc.strerror or exc}") from None
