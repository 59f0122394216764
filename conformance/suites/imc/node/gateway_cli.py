"""``imc-conformance gateway``: the Iridium/SMS gateway stand-in (``gateway.py``) on loopback HTTP, until
interrupted."""

from __future__ import annotations

import signal
import sys

from ....arguments import listen_port
from .gateway import GONE, MODES, SLOW


def add_command(sub) -> None:
    gateway = sub.add_parser(
        "gateway", help="run the Iridium/SMS gateway stand-in a node posts to (loopback HTTP)",
        description="An HTTP server on a loopback address standing in for a node's Iridium (or SMS) gateway, e.g. "
                    "DUNE's Simulators.Iridium 'Server Address'/'Server Port'. A message whose data holds "
                    "'imc-conformance:gateway=MODE' is handled in that mode, so a scenario can make the gateway "
                    "fail (the connection reset), slow (the answer late) or gone (it stops listening); any other "
                    "in --mode.")
    gateway.add_argument("--host", default="127.0.0.1", help="loopback address to listen on (default 127.0.0.1)")
    gateway.add_argument("--port", type=listen_port, default=8888, help="TCP port (default 8888; 0: any free)")
    gateway.add_argument("--mode", choices=MODES, default="ok", help="how unmarked messages are handled (default ok)")
    gateway.add_argument("--slow", type=float, default=SLOW, metavar="SECONDS",
                         help=f"how late a slow gateway answers (default {SLOW:g})")
    gateway.add_argument("--gone", type=float, default=GONE, metavar="SECONDS",
                         help=f"how long a gone gateway stays away (default {GONE:g})")
    gateway.set_defaults(func=command_gateway)


def command_gateway(args) -> int:
    from ....errors import UsageError
    from .gateway import GatewayServer

    if not (0 <= args.slow <= 3600 and 0 <= args.gone <= 3600):
        raise UsageError("--slow and --gone: seconds from 0 to 3600")
    try:
        server = GatewayServer((args.host, args.port), args.mode, args.slow, args.gone,
                               log=lambda line: print(line, file=sys.stderr, flush=True))
    except ValueError as exc:
        raise UsageError(f"--host {exc}") from None
    except OSError as exc:
        raise UsageError(f"cannot listen on {args.host}:{args.port}: {exc.strerror or exc}") from None
    host, port = server.server_address[:2]
    print(f"gateway stand-in on http://{f'[{host}]' if ':' in host else host}:{port}/ (unmarked messages: "
          f"{args.mode}); Ctrl-C stops it", file=sys.stderr, flush=True)
    signal.signal(signal.SIGTERM, _interrupt)
    try:
        server.serve_forever(poll_interval=0.2)
    except KeyboardInterrupt:
        return 0
    finally:
        server.stopping.set()
        server.server_close()
    return 0


def _interrupt(signum, frame):
    raise KeyboardInterrupt
