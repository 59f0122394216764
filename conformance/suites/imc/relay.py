"""What the relay needs of IMC, sans-IO: a node sends to the address a peer's Announce names (``imc+udp://IP:PORT/``,
imc-wire.md "IMC over UDP"), not to where the datagram came from, so the relay changes the addresses an Announce
announces to its own (the one the other side talks to): replies then come back through it, and the relay sends the
other side's datagrams to the address the Announce named (a node may send from any port). Nothing else is changed.
And the ambiguity under which a requester's resending of a lost query is recorded."""

from __future__ import annotations

import ipaddress
import re

from . import codec
from .definitions import Definitions
from .values import text_bytes

UDP_SERVICE = re.compile(r"imc\+udp://(\[[0-9a-fA-F:.]+\]|[^:/;\[\]]+):[0-9]+/?")
RESEND = ("resend-after-loss", "imc-wire#imc-over-udp-dunes-conventions")
INTRODUCTIONS = frozenset(["Announce"])  # a node ignores a system that has not announced itself (imc-wire.md)


class AnnounceRewriter:
    def __init__(self, defs: Definitions):
        self.defs = defs
        self.announce = defs.by_abbrev["Announce"].id

    def _services(self, data: bytes) -> tuple[dict, str, str] | None:
        """An Announce's message, byte order and services; None for any other datagram, or one that does not decode."""
        order = codec.byte_order_of(data)
        if order is None or len(data) < 4 or int.from_bytes(data[2:4], "little" if order == "le" else "big") != self.announce:
            return None
        try:
            message = codec.decode(self.defs, data)
            return message, order, text_bytes(message["fields"].get("services", "")).decode("utf-8", "replace")
        except ValueError:
            return None

    def reply_to(self, data: bytes) -> tuple[str, int] | None:
        """Where an Announce asks to be sent to: its first imc+udp service on loopback (host, port); else None (a
        node that announces no such service is answered where its datagrams come from)."""
        found = self._services(data)
        for match in UDP_SERVICE.finditer(found[2] if found else ""):
            host, port = match.group(1).strip("[]"), int(match.group(0).rstrip("/").rsplit(":", 1)[1])
            try:
                loopback = ipaddress.ip_address(host).is_loopback
            except ValueError:
                loopback = False
            if loopback and 0 < port < 65536:
                return host, port
        return None

    def __call__(self, data: bytes, facing: tuple) -> bytes | None:
        """The datagram with its Announce's imc+udp services naming ``facing`` (host, port); None when it is no
        Announce, names no such service, or does not decode (it is then carried unchanged, and judged as it is)."""
        found = self._services(data)
        if found is None:
            return None
        message, order, services = found
        host = f"[{facing[0]}]" if ":" in facing[0] else facing[0]
        changed = UDP_SERVICE.sub(f"imc+udp://{host}:{facing[1]}/", services)
        if changed == services:
            return None
        message["fields"]["services"] = changed
        try:
            return codec.encode(self.defs, message, order)
        except ValueError:
            return None
