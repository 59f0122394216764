"""Scenarios against the reference node (or a broken one) on virtual time, through the runner: the path the CLI
takes with --target, with an in-memory link instead of UDP."""

from __future__ import annotations

from imc_conformance.core.runner import run_cases
from imc_conformance.sessions.datagram import DatagramSession
from imc_conformance.sessions.virtual import VirtualLink
from imc_conformance.suites.imc.node import ReferenceNode
from imc_conformance.suites.imc.peer import DEFAULT_SYSTEM, ImcPeer

NODE, OWN = ("127.0.0.1", 6002), ("127.0.0.1", 6001)
PARAMS = {"peer": "imc-peer-1", "beacon": "b1", "sms_number": "+351000000000", "remote_system": 8208}
EVERYTHING = {"params": PARAMS, "effects": {"all"}}


def scenario_cases(cases, ids=None):
    return [c for c in cases if c.kind == "scenario" and (ids is None or c.id in ids)]


def virtual_session(suite, edition: str, node=None, **node_options):
    node = node or ReferenceNode(suite.defs, suite.behaviour, edition=edition, address=NODE, **node_options)
    link = VirtualLink(node, NODE, OWN)
    peer = ImcPeer(suite.defs, system=DEFAULT_SYSTEM, node=None, service=f"imc+udp://{OWN[0]}:{OWN[1]}/",
                   host=NODE[0], epoch=link.epoch)
    hello = {"implementation": "reference node (virtual)", "suites": ["imc"], "byte_orders": ["le", "be"],
             "kinds": ["scenario"]}
    return DatagramSession(link, peer, suite.wire, hello, startup=10.0), link


def run_virtual(suite, cases, edition=None, options=None, strict=False, **node_options):
    """The result of the scenarios among ``cases`` against a node made with ``node_options``, and its link."""
    edition = edition or suite.editions[0]
    session, link = virtual_session(suite, edition, **node_options)
    result = run_cases(session, suite, scenario_cases(cases), edition=edition, adapter="virtual",
                       options=EVERYTHING if options is None else options, strict=strict, clock=link.now,
                       started="2026-01-01T00:00:00+00:00")
    return result, link
