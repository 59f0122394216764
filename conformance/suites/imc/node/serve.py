"""``imc-conformance serve``: the reference node (or a broken one) on a UDP socket, until interrupted."""

from __future__ import annotations

import select
import signal
import sys
import time

from ....arguments import chosen_edition, listen_port, probability
from .breaks import BREAKS, VARIANTS
from ....core.wording import counted


def add_command(sub) -> None:
    serve = sub.add_parser("serve", help="run the reference IMC node (or a broken one) on loopback UDP",
                           description="A simulated IMC node implementing the seeds' behaviour, with a simulated "
                                       "acoustic channel and fake Iridium/SMS gateways. It answers only systems that "
                                       "announce an imc+udp service to it, and announces by unicast only.")
    serve.add_argument("--host", default="127.0.0.1", help="address to listen on (default 127.0.0.1)")
    serve.add_argument("--port", type=listen_port, default=6002, help="UDP port (default 6002, DUNE's; 0: any free)")
    serve.add_argument("--system", default="imc-reference/0x00A0", metavar="NAME/ID",
                       help="the node's name and IMC id (default imc-reference/0x00A0)")
    serve.add_argument("--peer", action="append", default=[], metavar="NAME[:METRES]",
                       help="a system on the simulated acoustic channel and its range (repeatable; default "
                            "imc-peer-1:150 and imc-peer-2:1200)")
    serve.add_argument("--edition", help="the IMC edition it speaks (default: the suite's first)")
    serve.add_argument("--loss", type=probability, default=0.0,
                       help="drop this share of idempotent requests and replies (never more than two of one message in a row)")
    serve.add_argument("--dup", type=probability, default=0.0, help="send this share of replies twice")
    serve.add_argument("--seed", type=int, default=0, help="seed of the loss and duplication (default 0)")
    serve.add_argument("--break", dest="broken", choices=sorted(BREAKS), metavar="NAME",
                       help="break one rule: " + "; ".join(f"{k}: {v}" for k, v in BREAKS.items()))
    serve.add_argument("--variant", choices=sorted(VARIANTS), metavar="NAME",
                       help="a correct node taking another reading the seeds allow (vectors/imc/ambiguities.json): "
                            + "; ".join(f"{k}: {v}" for k, v in VARIANTS.items()))
    serve.add_argument("--only-to-itself", action="append", default=[], metavar="CAPABILITY",
                       help="serve this capability (vectors/imc/exchanges.json capabilities) only to the node's own "
                            "system, as DUNE serves acoustic-request; run the suite with claims that say so "
                            '({"capabilities": {"acoustic-request": "self"}})')
    serve.set_defaults(func=command_serve)


def parse_system(text: str) -> tuple[str, int]:
    name, sep, number = text.rpartition("/")
    try:
        system = int(number, 0)
    except ValueError:
        raise ValueError(f"--system {text!r}: expected NAME/ID, e.g. imc-reference/0x00A0") from None
    if not sep or not name or not 0 <= system < 0xFFFF:
        raise ValueError(f"--system {text!r}: expected NAME/ID with an id below 0xFFFF")
    return name, system


def parse_peers(items: list[str]) -> dict[str, float] | None:
    if not items:
        return None
    peers = {}
    for item in items:
        name, _, metres = item.partition(":")
        try:
            peers[name] = float(metres or 500.0)
        except ValueError:
            raise ValueError(f"--peer {item!r}: expected NAME[:METRES]") from None
        if not name or "," in name or not 0 < peers[name] < 100_000:
            raise ValueError(f"--peer {item!r}: a name without commas and a range in metres (0-100000)")
    return peers


def command_serve(args) -> int:
    from ....errors import UsageError
    from ....sessions.udp import bound_socket, group_address, resolve, url
    from .. import load
    from .node import ReferenceNode

    suite = load()
    edition = chosen_edition(suite, args.edition)
    try:
        name, system = parse_system(args.system)
        peers = parse_peers(args.peer)
        family, address = resolve(args.host, args.port, "--host")
        unknown = [c for c in args.only_to_itself if c not in suite.behaviour["capabilities"]]
        if unknown:
            raise ValueError(f"--only-to-itself {unknown[0][:40]!r}: one of {', '.join(suite.behaviour['capabilities'])}")
    except ValueError as exc:
        raise UsageError(str(exc)) from exc
    if group_address(address[0]):
        raise UsageError(f"--host {args.host}: {group_address(address[0])}; the reference node listens on one address")
    try:
        sock = bound_socket(family, address, f"cannot listen on {args.host}:{args.port}")
    except ValueError as exc:
        raise UsageError(str(exc)) from exc
    offset = time.time() - time.monotonic()
    node = ReferenceNode(suite.defs, suite.behaviour, edition=edition, address=sock.getsockname()[:2], name=name,
                         system=system, peers=peers, loss=args.loss, dup=args.dup, seed=args.seed, broken=args.broken,
                         variant=args.variant, epoch0=offset, only_to_itself=tuple(args.only_to_itself))
    print(f"reference IMC node {name} (0x{system:04X}, {edition}) on {url(*sock.getsockname()[:2])}"
          + (f", broken: {args.broken}" if args.broken else "") + (f", variant: {args.variant}" if args.variant else "")
          + (f", only to itself: {', '.join(args.only_to_itself)}" if args.only_to_itself else "")
          + "; Ctrl-C stops it", file=sys.stderr, flush=True)
    signal.signal(signal.SIGTERM, _interrupt)  # kill stops it as Ctrl-C does, with its summary
    try:
        serve_forever(sock, node)
    except KeyboardInterrupt:
        print(f"stopped; dropped {counted(node.dropped, 'malformed datagram')} and {node.unjudged} nested deeper than "
              f"the reference codec follows; ignored {counted(node.refused, 'announced service')} (names, or the "
              "contact table full)",
              file=sys.stderr)
        return 0
    finally:
        sock.close()
    return 0


def _interrupt(signum, frame):
    raise KeyboardInterrupt


def serve_forever(sock, node) -> None:
    from ....sessions.udp import MAX_DATAGRAM, group_address

    while True:
        deadline = node.deadline
        wait = 1.0 if deadline is None else max(0.0, min(1.0, deadline - time.monotonic()))
        ready, _, _ = select.select([sock], [], [], wait)
        if ready:
            try:
                data, source = sock.recvfrom(MAX_DATAGRAM)
            except OSError:
                data = None
            if data is not None:
                node.receive(time.monotonic(), data, source[:2])
        for destination, frame in node.due(time.monotonic()):
            if group_address(destination[0]) is None:  # never to a group, whatever a contact announced
                try:
                    sock.sendto(frame, destination)
                except OSError:
                    pass
