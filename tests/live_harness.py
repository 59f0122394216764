"""Live cases against the reference node (or a broken one) on virtual time, through the runner: the path the CLI
takes with --target, with an in-memory link instead of UDP."""

from __future__ import annotations

import json

from imc_conformance.core.runner import run_cases
from imc_conformance.paths import VECTORS
from imc_conformance.sessions.datagram import DatagramSession
from imc_conformance.sessions.virtual import VirtualLink
from imc_conformance.suites.imc.node import ReferenceNode
from imc_conformance.suites.imc.peer import DEFAULT_SYSTEM, ImcPeer

NODE, OWN = ("127.0.0.1", 6002), ("127.0.0.1", 6001)
PARAMS = {"peer": "imc-peer-1", "beacon": "b1", "sms_number": "+351000000000", "remote_system": 8208,
          "gateway": "http://127.0.0.1:8888/"}
# what the reference node claims: every capability, for any system (LBL navigation among them)
CLAIMS = {name: "any" for name in json.loads((VECTORS / "imc" / "exchanges.json").read_text())["capabilities"]}
EVERYTHING = {"params": PARAMS, "effects": {"all"}, "claims": CLAIMS}
LIVE_KINDS = ("scenario", "robustness")


def scenario_cases(cases, ids=None, kinds=("scenario",)):
    return [c for c in cases if c.kind in kinds and (ids is None or c.id in ids)]


def virtual_session(suite, edition: str, node=None, restartable: bool = False, restarted=None, recorder=None,
                    **node_options):
    """A session with a node on virtual time; ``restartable``: the session may restart it (a fresh node made
    with the same options, passed through ``restarted`` if given), as --restart-cmd lets it restart a real one."""
    def fresh():
        return ReferenceNode(suite.defs, suite.behaviour, edition=edition, address=NODE, **node_options)

    link = VirtualLink(node or fresh(), NODE, OWN)
    peer = ImcPeer(suite.defs, system=DEFAULT_SYSTEM, node=None, service=f"imc+udp://{OWN[0]}:{OWN[1]}/",
                   host=NODE[0], epoch=link.epoch)
    hello = {"implementation": "reference node (virtual)", "suites": ["imc"], "byte_orders": ["le", "be"],
             "kinds": list(LIVE_KINDS)}

    def restart():
        link.node = fresh() if restarted is None else restarted(fresh(), link.now())
        link.restarts += 1
        return None

    link.restarts = 0
    return DatagramSession(link, peer, suite.wire, hello, startup=10.0, restart=restart if restartable else None,
                           recorder=recorder), link


def run_virtual(suite, cases, edition=None, options=None, strict=False, kinds=("scenario",), restartable=False,
                restarted=None, recorder=None, **node_options):
    """The result of the live cases of ``kinds`` among ``cases`` against a node made with ``node_options``, and
    its link. The robustness phase replays the vector cases among ``cases``."""
    edition = edition or suite.editions[0]
    session, link = virtual_session(suite, edition, restartable=restartable, restarted=restarted, recorder=recorder,
                                    **node_options)
    options = dict(EVERYTHING if options is None else options)
    options.setdefault("corpus", tuple(c for c in cases if c.kind == "vector"))
    options.setdefault("robustness", "robustness" in kinds)
    options.setdefault("restart", restartable)
    options.setdefault("replay_effects", "all" in options.get("effects", ()))
    result = run_cases(session, suite, scenario_cases(cases, kinds=kinds), edition=edition, adapter="virtual",
                       options=options, strict=strict, clock=link.now, started="2026-01-01T00:00:00+00:00")
    return result, link


def recorded_run(suite, cases, path, **node_options):
    """The result of the scenarios (seed profile, edition 5.4.30) against a node made with ``node_options``, recorded
    as a live run records it into the pcapng ``path`` (for ``pcap`` to judge again)."""
    from imc_conformance.capture.recording import Recorder, about_run

    options = dict(EVERYTHING, time_scale=1.0, profile=suite.profile("seed"))
    ids = [c.id for c in cases if c.kind == "scenario"]
    recorder = Recorder(path, about_run("imc", "imc-5.4.30", ids, options, "udp://127.0.0.1:6002", None, None, 10.0))
    try:
        return run_virtual(suite, cases, "imc-5.4.30", options=options, recorder=recorder, **node_options)[0]
    finally:
        recorder.close(complete=True)
