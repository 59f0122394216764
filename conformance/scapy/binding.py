"""Binding the IMC layer to the UDP ports DUNE uses, so that captures and sniffing dissect IMC."""

from __future__ import annotations

from scapy.layers.inet import UDP
from scapy.packet import bind_bottom_up, bind_top_down, split_bottom_up, split_top_down

from ..suites.imc.capture import PORTS
from .frame import IMC

DEFAULT_PORT = 6001


def bind() -> None:
    """Dissect a UDP datagram from or to one of ``PORTS`` as IMC; ``UDP()/IMC()`` gets ports 6001 → 6001."""
    unbind()
    for port in sorted(PORTS):
        bind_bottom_up(UDP, IMC, sport=port)
        bind_bottom_up(UDP, IMC, dport=port)
    bind_top_down(UDP, IMC, sport=DEFAULT_PORT, dport=DEFAULT_PORT)


def unbind() -> None:
    """Undo ``bind()``."""
    for port in sorted(PORTS):
        split_bottom_up(UDP, IMC, sport=port)
        split_bottom_up(UDP, IMC, dport=port)
    split_top_down(UDP, IMC, sport=DEFAULT_PORT, dport=DEFAULT_PORT)
