"""Importing this module binds the IMC layer to its UDP ports: ``import imc_conformance.scapy.bound``."""

from . import bind

bind()
