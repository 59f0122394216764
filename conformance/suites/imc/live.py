"""A live IMC node as a session: UDP to the target, with the manners of an IMC peer."""

from __future__ import annotations

from ...sessions.datagram import DatagramSession
from ...sessions.replay import ReplayLink
from ...sessions.udp import UdpTransport, group_address, parse_endpoint, resolve, route_source
from .peer import DISCOVERY_PORTS, ImcPeer, session_system


def open_target(suite, target: str, *, bind: str | None = None, src: int | None = None, dst: int | None = None,
                allow_group: bool = False, startup: float = 10.0, restart=None, recorder=None,
                first_unique: int | None = None) -> DatagramSession:
    """The session for ``target`` (``udp://HOST:PORT``, ``imc+udp://HOST:PORT/``); ValueError with a one-line
    reason for a malformed URL, a group address, a host that does not resolve or a bind that fails. Without
    ``src`` the session's id is chosen by ``first_unique`` (``peer.session_system``)."""
    host, port = parse_endpoint(target, "--target")
    family, address = resolve(host, port, "--target")
    why = group_address(address[0])
    if why and not allow_group:
        raise ValueError(f"--target {target}: {why}; a run talks to one node (--allow-multicast overrides)")
    system = session_system(src, first_unique)
    if system == dst:
        raise ValueError(f"--src and --dst are both {system:#06x}: the session needs an id of its own")
    bind_host, bind_port = parse_endpoint(bind, "--bind", default_port=0) if bind else (route_source(family, address), 0)
    _, bind_address = resolve(bind_host, bind_port, "--bind")
    why = group_address(bind_address[0])
    if why and not allow_group:
        raise ValueError(f"--bind {bind}: {why} (--allow-multicast overrides)")
    transport = UdpTransport(address, bind_address, family, listen=reversed(DISCOVERY_PORTS))  # 30100 left to the node
    own_host, own_port = transport.address[:2]
    shown = f"[{own_host}]" if ":" in own_host else own_host
    peer = ImcPeer(suite.defs, system=system, node=dst, service=f"imc+udp://{shown}:{own_port}/", host=address[0],
                   epoch=transport.epoch, chosen=src is None)
    hello = {"implementation": f"IMC node at {target}", "suites": [suite.name], "byte_orders": list(suite.encodings),
             "kinds": ["scenario", "robustness"]}
    return DatagramSession(transport, peer, suite.wire, hello, startup, restart, recorder,
                           first_unique=1000 if first_unique is None else first_unique)


def open_replay(suite, link: ReplayLink, *, target: str, src: int | None, dst: int | None, startup: float,
                first_unique: int | None = None) -> DatagramSession:
    """A session replaying a recorded run (``link``) on virtual time, with the recorded run's settings."""
    host, port = link.address[:2]
    shown = f"[{host}]" if ":" in host else host
    peer = ImcPeer(suite.defs, system=session_system(src, first_unique), node=dst,
                   service=f"imc+udp://{shown}:{port}/", host=link.target[0], epoch=link.epoch)
    hello = {"implementation": f"IMC node at {target} (replayed)", "suites": [suite.name],
             "byte_orders": list(suite.encodings), "kinds": ["scenario"]}
    return DatagramSession(link, peer, suite.wire, hello, startup, recorder=link,
                           first_unique=1000 if first_unique is None else first_unique)
