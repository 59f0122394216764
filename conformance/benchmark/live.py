"""Live rows: the scenario set against the reference node (loopback, and protocol time against every broken
node), and the robustness phase."""

from __future__ import annotations

import statistics
import subprocess
import sys

from ..core.runner import run_cases
from .measure import EDITION, LIVE_PARAMS, command_env, median_of, timed, whole


def live_rows(suite, everything, repeat: int, robustness: bool) -> dict[str, float]:
    """The scenario set against the reference node: whole process over loopback; in protocol time against it and
    every broken node (virtual: the waits a live run makes); once, the robustness phase over loopback."""
    import re

    from ..sessions.datagram import DatagramSession
    from ..sessions.virtual import VirtualLink
    from ..suites.imc.node import BREAKS, ReferenceNode
    from ..suites.imc.peer import DEFAULT_SYSTEM, ImcPeer

    scenarios = [c for c in everything if c.kind == "scenario"]
    options = {"params": LIVE_PARAMS, "effects": {"all"}, "profile": suite.profile("seed"),
               "corpus": tuple(c for c in everything if c.kind == "vector")}

    def protocol_time(broken: str | None) -> float:
        node = ReferenceNode(suite.defs, suite.behaviour, edition=EDITION, address=("127.0.0.1", 6002), broken=broken)
        link = VirtualLink(node, ("127.0.0.1", 6002), ("127.0.0.1", 6001))
        peer = ImcPeer(suite.defs, system=DEFAULT_SYSTEM, node=None, service="imc+udp://127.0.0.1:6001/",
                       host="127.0.0.1", epoch=link.epoch)
        hello = {"implementation": "virtual", "suites": ["imc"], "byte_orders": ["le", "be"], "kinds": ["scenario"]}
        run_cases(DatagramSession(link, peer, suite.wire, hello, startup=10.0), suite, scenarios, edition=EDITION,
                  adapter="virtual", options=options, clock=link.now)
        return link.now()
    clean = protocol_time(None)
    broken = {name: protocol_time(name) for name in BREAKS if name != "leaks-on-drop"}  # that one needs the flood
    slowest = max(broken, key=broken.get)
    out = {"live reference": round(clean, 3), "live ratio": broken[slowest] / clean,
           "live median ratio": statistics.median(broken.values()) / clean}
    out |= {f"live ratio {name}": seconds / clean for name, seconds in broken.items()}
    node = subprocess.Popen([sys.executable, "-m", "imc_conformance.cli", "serve", "--port", "0"],
                            stderr=subprocess.PIPE, text=True)
    try:
        url = re.search(r"udp://\S+?(?=[;,])", node.stderr.readline())[0]
        params = [a for k, v in LIVE_PARAMS.items() for a in ("--param", f"{k}={v}")]
        out["live"] = median_of(repeat, lambda: whole(["run", "--target", url, "--allow-effects", *params,
                                                        "--no-progress"], command_env()))
        if robustness:
            out["robustness"] = timed(lambda: whole(["run", "--target", url, "--allow-effects", *params, "--robustness",
                                                     "--message", "AcousticSystemsQuery", "--no-progress"], command_env()))
    finally:
        node.terminate()
        node.wait(timeout=10)
        node.stderr.close()
    print(f"live: {len(scenarios)} scenarios against the reference node over loopback, whole process: "
          f"{out['live']:.3f} s; in protocol time {clean:.1f} s; the slowest broken node ({slowest}) "
          f"{broken[slowest]:.1f} s ({out['live ratio']:.1f}x), the median one {out['live median ratio']:.2f}x"
          + (f"; the robustness phase once: {out['robustness']:.1f} s" if robustness else ""))
    print("  protocol time per broken node, against the reference node's: " + ", ".join(
        f"{k} {v:.1f} s ({v / clean:.2f}x)" for k, v in sorted(broken.items(), key=lambda kv: -kv[1])))
    return out
