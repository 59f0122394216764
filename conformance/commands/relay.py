"""``imc-conformance relay``: stand between a console and a vehicle on loopback, carry their datagrams both ways through
a link that fails as told (``--impair``, reproducible from ``--seed``), and judge both sides as a watcher at each
would (``relay.core``, sans-IO: this module only moves datagrams and keeps time). Reports on Ctrl-C or after
``--duration``; ``--pcap`` records what each side sent and received."""

from __future__ import annotations

import datetime as dt
import ipaddress
import select
import signal
import sys
import time

from ..arguments import positive_seconds
from ..errors import UsageError
from .options import add_judging, add_reports

REFRESH = 1.0  # seconds between progress lines


def add(sub) -> None:
    relay = sub.add_parser("relay", help="relay a console and a vehicle on loopback through an impaired link, judging both",
                           description="Listens where the console sends (udp://ADDR:PORT), forwards to --vehicle and "
                                       "back, through a link that loses, delays, duplicates, reorders, corrupts, caps "
                                       "or cuts datagrams as --impair says; judges each side's exchanges as a watcher "
                                       "at that side would. Loopback addresses only.")
    relay.add_argument("listen", metavar="udp://ADDR:PORT", help="where the console sends (the relay's own socket)")
    relay.add_argument("--vehicle", required=True, metavar="udp://ADDR:PORT", help="the vehicle's address")
    relay.add_argument("--via", metavar="ADDR:PORT", help="the relay's socket the vehicle talks to (default: the listen "
                                                          "address, any port)")
    relay.add_argument("--impair", default="", metavar="SPEC",
                       help="both directions: loss=P,burst=N,delay=S,jitter=S,distribution=uniform|normal|exponential,"
                            "duplicate=P,reorder=P,hold=S,corrupt=P,rate=BITS_PER_S,down=START-END[+START-END]")
    relay.add_argument("--to-vehicle", metavar="SPEC", help="the console-to-vehicle direction (instead of --impair)")
    relay.add_argument("--to-console", metavar="SPEC", help="the vehicle-to-console direction (instead of --impair)")
    relay.add_argument("--seed", type=int, default=0, help="seed of every impairment's draws (default 0)")
    relay.add_argument("--duration", type=positive_seconds, metavar="SECONDS", help="stop after this long (default: Ctrl-C)")
    relay.add_argument("--pcap", metavar="FILE", help="record what each side sent and received (pcapng)")
    add_judging(relay)
    add_reports(relay)
    relay.set_defaults(func=command)


def loopback(text: str, what: str, bind: bool = False) -> tuple[int, tuple]:
    """(family, address) of a loopback endpoint; UsageError in one line for any other."""
    from ..relay.core import LOOPBACK_NOT_HOSTS
    from ..sessions.udp import parse_endpoint, resolve

    try:
        host, port = parse_endpoint(text, what, default_port=0 if bind else None)
        family, address = resolve(host, port, what)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    ip = ipaddress.ip_address(address[0].split("%")[0])
    if not ip.is_loopback:
        raise UsageError(f"{what} {text}: {address[0]} is not a loopback address; the relay talks on loopback only "
                         "(never to a group, a broadcast or another host)")
    if ip in LOOPBACK_NOT_HOSTS:
        raise UsageError(f"{what} {text}: {address[0]} is the loopback network's {LOOPBACK_NOT_HOSTS[ip]} address, "
                         "no one host's; the relay talks to one host on loopback (never to a group or a broadcast)")
    return family, address


def impairments(args) -> dict:
    from ..relay.impairment import parse

    out = {}
    for side, option, text in (("console", "--to-vehicle", args.to_vehicle), ("vehicle", "--to-console", args.to_console)):
        given = text if text is not None else args.impair
        try:
            out[side] = parse(given)
        except ValueError as exc:
            raise UsageError(f"{option if text is not None else '--impair'}: {exc}") from None
    return out


def command(args) -> int:
    from ..capture.judge import CaptureJudge, Selection
    from ..capture.recording import Recorder
    from ..relay.core import SIDES, Relay, merged
    from ..relay.impairment import Link
    from ..render.terminal import print_result
    from ..sessions.udp import bound_socket, url
    from .output import report_targets, terminal, write_reports
    from .pcap import capture_rules
    from .provenance import provenance

    targets = report_targets(args)
    if args.port:
        raise UsageError("--port is not for relay: every datagram it carries is judged, whatever its port")
    links_given = impairments(args)
    family, listen = loopback(args.listen, "relay")
    vfamily, vehicle = loopback(args.vehicle, "--vehicle")
    via_text = args.via or (f"[{listen[0]}]:0" if ":" in listen[0] else f"{listen[0]}:0")
    via_family, via = loopback(via_text, "--via", bind=True)
    if vfamily != via_family:
        if args.via:
            raise UsageError(f"--via {via_text} and --vehicle {args.vehicle} are not of the same address family")
        other = "[::1]:0" if ":" in vehicle[0] else "127.0.0.1:0"
        raise UsageError(f"--vehicle {args.vehicle} and the relay's address {args.listen} are not of the same address "
                         f"family: give --via {other}, the relay's socket facing the vehicle")
    if vehicle[:2] in (listen[:2], via[:2]):  # the relay would carry its own datagrams as the vehicle's
        own = "relay" if vehicle[:2] == listen[:2] else "--via"
        raise UsageError(f"--vehicle {args.vehicle} is the relay's own socket ({own}): give the vehicle's address")
    suite, rules, edition = capture_rules(args)
    try:
        sockets = {"console": bound_socket(family, listen, f"relay {args.listen}")}
        sockets["vehicle"] = bound_socket(via_family, via, f"--via {via_text}")
    except ValueError as exc:
        for sock in locals().get("sockets", {}).values():
            sock.close()
        raise UsageError(str(exc)) from None
    for sock in sockets.values():
        sock.setblocking(False)
    facing = {side: sock.getsockname()[:2] for side, sock in sockets.items()}
    ports = frozenset([facing["console"][1], facing["vehicle"][1], vehicle[1]])

    def judge() -> CaptureJudge:
        return CaptureJudge(suite.name, suite.capture_rules(), edition,
                            Selection(ports=ports, groups=frozenset(args.message), listed=args.list_frames,
                                      scale=args.time_scale))

    setting = {"to-vehicle": links_given["console"].describe(), "to-console": links_given["vehicle"].describe(),
               "seed": args.seed}
    recorder = None
    if args.pcap:
        try:
            recorder = Recorder(args.pcap, {"suite": suite.name, "edition": edition, "impairment": setting,
                                            "listen": list(facing["console"]), "vehicle": list(vehicle)},
                                prefix="imc-conformance relay ")
        except OSError as exc:
            raise UsageError(f"--pcap {args.pcap}: {exc.strerror or exc}") from None
    relay = Relay({side: judge() for side in SIDES},
                  {side: Link(links_given[side], args.seed, side) for side in SIDES}, facing,
                  {"console": None, "vehicle": vehicle}, record=recorder.record if recorder else None,
                  **suite.relay_hooks())
    console = terminal()
    shown = f"udp://{args.listen.split('://')[-1]}"
    print(f"imc-conformance: relaying {shown} <-> {args.vehicle} (via {url(*facing['vehicle'])})"
          f"{'' if all(i.none for i in links_given.values()) else ' through an impaired link'} (Ctrl-C to stop)",
          file=sys.stderr, flush=True)
    started = dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds")
    offset = time.time() - time.monotonic()
    began = time.monotonic()
    end = began + args.duration if args.duration else float("inf")
    stopping: list[int] = []
    handlers = {sig: signal.signal(sig, lambda signum, frame: stopping.append(signum))
                for sig in (signal.SIGINT, signal.SIGTERM)}
    io = _Io(sockets, relay, offset)
    try:
        shown_at = began
        while not stopping and time.monotonic() < end:
            deadline = relay.deadline
            now = time.monotonic()
            wait = min(REFRESH, end - now, max(0.0, deadline - offset - now) if deadline is not None else REFRESH)
            io.step(max(0.0, wait))
            if time.monotonic() - shown_at >= 10 * REFRESH and not console.is_terminal:
                shown_at = time.monotonic()
                print(f"imc-conformance: {sum(c['sent'] for c in relay.counts.values()):,} datagrams relayed",
                      file=sys.stderr, flush=True)
    finally:
        for sig, handler in handlers.items():
            signal.signal(sig, handler)
        for sock in sockets.values():
            sock.close()
    now = time.monotonic() + offset
    relay.finish(now)
    if recorder:
        recorder.close(complete=False)  # "run complete" is a recorded run's word, not a relay's
    duration = round(time.monotonic() - began, 3)
    results = {side: relay.judges[side].result(implementation=f"the {side}", started=started, duration=duration,
                                               strict=args.strict, title=suite.title, until=now) for side in SIDES}
    silent = not relay.counts["vehicle"]["sent"]
    result = merged(results, args.strict, judged=("console",) if silent else SIDES)
    result.implementation = f"console at {shown} and vehicle at {args.vehicle}, through the relay"
    result.adapter = "relay"
    result.notes = relay.notes() + io.notes() + ([f"--pcap: {recorder.failed}"] if recorder and recorder.failed else []) \
        + result.notes
    result.provenance = provenance(args, suite, {"message": args.message, "impairment": setting})
    if silent:
        result.notes.insert(0, f"nothing came from the vehicle at {args.vehicle} in {duration:g} s: nothing is judged "
                               "of the vehicle")
    print_result(result, console)
    if silent:
        print(f"imc-conformance: nothing came from the vehicle at {args.vehicle} in {duration:g} s (is it running, "
              "and sending to the relay?): nothing judged of it", file=sys.stderr)
    return 2 if write_reports(result, targets, console) or silent else result.exit_code()


class _Io:
    """The relay's two sockets: what arrives is handed to the relay, what it says is due is sent."""

    def __init__(self, sockets: dict, relay, offset: float):
        self.sockets, self.relay, self.offset = sockets, relay, offset
        self.strangers = 0  # datagrams from neither side (another sender on the listen port, or not the vehicle)
        self.kernel = {side: 0 for side in sockets}  # datagrams the kernel dropped on each socket

    def step(self, wait: float) -> None:
        from ..sessions.udp import read

        ready, _, _ = select.select(list(self.sockets.values()), [], [], wait)
        for side, sock in self.sockets.items():
            if sock not in ready:
                continue
            for _ in range(1000):
                try:
                    data, source, dropped = read(sock)
                except OSError:  # nothing more, or an ICMP error reported on the socket
                    break
                now = time.monotonic() + self.offset
                if dropped is not None and dropped > self.kernel[side]:
                    for judge in self.relay.judges.values():
                        judge.losses(now, now, dropped - self.kernel[side])
                    self.kernel[side] = dropped
                if not self.relay.accepts(side, source[:2], data):
                    self.strangers += 1
                    continue
                self.relay.inbound(now, side, data, source[:2])
        self.relay.due(time.monotonic() + self.offset, self._send)

    def _send(self, to: str, data: bytes) -> bool:
        try:
            self.sockets[to].sendto(data, self.relay.endpoints[to])
        except OSError:
            return False
        return True

    def notes(self) -> list[str]:
        out = [f"{self.strangers} datagrams from neither the console nor the vehicle were dropped"] if self.strangers else []
        out += [f"the kernel dropped {n} datagrams on the {side}'s socket before the relay read them"
                for side, n in self.kernel.items() if n]
        return out
