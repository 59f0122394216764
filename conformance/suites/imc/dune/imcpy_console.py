"""A console nobody here wrote, for ``make dune-relay --console imcpy``: imcpy's actor framework (``imcpy.actors``, with
which LSTS scripts vehicles) asking DUNE, through the relay, what it serves: AcousticSystemsQuery, LblConfig GET_CFG
and HistoricDataQuery QUERY in turn, every few seconds, each answered or not, for a given time.

imcpy finds a node by the Announce it multicasts. The relay's DUNE announces nothing (an Announce on loopback would
name DUNE's own address, and the traffic would go around the relay), so the actor is given DUNE as a fixed node (imcpy's
``IMCNode(is_fixed=True)``) whose imc+udp service is the relay's socket, and it sends its own Announce there as well as
to the multicast group: the relay then answers it at the address that Announce names. imcpy's multicast stays inside
the private namespace, where no DUNE listens for it. Run only inside that namespace (``dune/relay.py`` starts it)."""

from __future__ import annotations

import argparse
import json
import time
from collections import Counter

import imcpy
from imcpy.actors import DynamicActor
from imcpy.decorators import Periodic, Subscribe
from imcpy.node import IMCNode

CONSOLE_ID = 0x3334  # imcpy's own default system id
ASK_EVERY = 3.0  # seconds between queries


class Console(DynamicActor):
    """Asks ``vehicle`` (its IMC id and name) through the relay at ``relay`` (host, port) for ``seconds``."""

    def __init__(self, relay: tuple[str, int], vehicle: int, name: str, seconds: float):
        super().__init__(imc_id=CONSOLE_ID)
        node = IMCNode(src=vehicle, sys_name=name, is_fixed=True)
        node.update_services(f"imc+udp://{relay[0]}:{relay[1]}/")
        self.add_node(node)
        self.heartbeat.append(vehicle)
        self.vehicle, self.seconds, self.began = vehicle, seconds, time.monotonic()
        self.turn = 0
        self.asked: Counter = Counter()
        self.answered: Counter = Counter()
        self.waiting: dict[tuple, str] = {}  # what each query awaits -> the query's name

    @Periodic(5)
    def introduce(self):
        """The actor's Announce, to DUNE through the relay, naming the actor's own socket."""
        if self._port_imc:
            self.announce.services = f"imc+udp://127.0.0.1:{self._port_imc}/"
            self.send(self.vehicle, self.announce)

    @Periodic(ASK_EVERY)
    def ask(self):
        kind = ("AcousticSystemsQuery", "LblConfig", "HistoricDataQuery")[self.turn % 3]
        self.turn += 1
        if kind == "AcousticSystemsQuery":
            query, awaited = imcpy.AcousticSystemsQuery(), ("AcousticSystems", None)
        elif kind == "LblConfig":
            query = imcpy.LblConfig()
            query.op = imcpy.LblConfig.OperationEnum.GET_CFG
            awaited = ("LblConfig", None)
        else:
            query = imcpy.HistoricDataQuery()
            query.req_id, query.type, query.max_size = self.turn, imcpy.HistoricDataQuery.RequestTypeEnum.QUERY, 1000
            awaited = ("HistoricDataQuery", self.turn)
        self.asked[kind] += 1
        self.waiting[awaited] = kind
        self.send(self.vehicle, query)

    @Subscribe(imcpy.AcousticSystems, imcpy.LblConfig, imcpy.HistoricDataQuery)
    def reply(self, msg):
        name = type(msg).__name__
        if name == "LblConfig" and msg.op != imcpy.LblConfig.OperationEnum.CUR_CFG:
            return
        if name == "HistoricDataQuery" and msg.type != imcpy.HistoricDataQuery.RequestTypeEnum.REPLY:
            return
        kind = self.waiting.pop((name, msg.req_id if name == "HistoricDataQuery" else None), None)
        if kind is not None:
            self.answered[kind] += 1

    @Periodic(1)
    def until(self):
        if time.monotonic() - self.began >= self.seconds:
            self.stop()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--relay", required=True, metavar="PORT", type=int, help="the relay's port on 127.0.0.1")
    parser.add_argument("--vehicle", required=True, type=lambda text: int(text, 0), help="DUNE's IMC id")
    parser.add_argument("--name", required=True, help="DUNE's system name")
    parser.add_argument("--seconds", type=float, required=True)
    parser.add_argument("--json", required=True, help="where to write what it asked and what was answered")
    args = parser.parse_args(argv)
    console = Console(("127.0.0.1", args.relay), args.vehicle, args.name, args.seconds)
    console.run()
    with open(args.json, "w", encoding="utf-8") as out:
        json.dump({"asked": dict(console.asked), "answered": dict(console.answered)}, out)
    print("imcpy console: " + ", ".join(f"{kind} {console.answered[kind]}/{n} answered"
                                        for kind, n in sorted(console.asked.items())))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
