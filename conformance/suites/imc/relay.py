"""What the relay needs of IMC, sans-IO: a node sends to the address a peer's Announce names (``imc+udp://IP:PORT/``,
imc-wire.md "IMC over UDP"), not to where the datagram came from, so the relay changes the addresses an Announce
announces to its own (the one the other side talks to): replies then come back through it. Nothing else is changed.
And the ambiguity under which a requester's resending of a lost query is recorded."""

from __future__ import annotations

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

    def __call__(self, data: bytes, facing: tuple) -> bytes | None:
        """The datagram with its Announce's imc+udp services naming ``facing`` (host, port); None when it is no
        Announce, names no such service, or does not decode (it is then carried unchanged, and judged as it is)."""
        order = codec.byte_order_of(data)
        if order is None or len(data) < 4 or int.from_bytes(data[2:4], "little" if order == "le" else "big") != self.announce:
            return None
        try:
            message = codec.decode(self.defs, data)
            services = text_bytes(message["fields"].get("services", "")).decode("utf-8", "replace")
        except ValueError:
            return None
        host = f"[{facing[0]}]" if ":" in facing[0] else facing[0]
        changed = UDP_SERVICE.sub(f"imc+udp://{host}:{facing[1]}/", services)
        if changed == services:
            return None
        message["fields"]["services"] = changed
        try:
            return codec.encode(self.defs, message, order)
        except ValueError:
            return None
