"""The reference node's HistoricData store under a console's flood of samples: bounded, the highest priority kept,
every QUERY answered in one pass with a reply that fits its max_size and a datagram (sans-IO, no clock)."""

from __future__ import annotations

import pytest

from imc_conformance.suites.imc import codec
from imc_conformance.suites.imc.node.history import DATAGRAM, KEPT_MAX, KEPT_SLACK
from imc_conformance.suites.imc.node.node import ReferenceNode

NODE, CONSOLE = ("127.0.0.1", 6002), ("127.0.0.1", 7000)
CONSOLE_ID, NODE_ID = 0x3001, 0x00A0
PER_DATAGRAM = 4000  # samples of 15 bytes: a 60 kB datagram


def frame(defs, abbrev: str, fields: dict) -> bytes:
    header = {"timestamp": 1.7e9, "src": CONSOLE_ID, "src_ent": 0, "dst": NODE_ID, "dst_ent": 255}
    return codec.encode(defs, {"abbrev": abbrev, "header": header, "fields": fields}, "le")


def sample(priority: int, x: int = 0) -> dict:
    return {"abbrev": "HistoricSample",
            "fields": {"sys_id": CONSOLE_ID, "priority": priority, "x": x, "y": 0, "z": 0, "t": 0, "sample": None}}


class Measured:
    """The node's wire, counting the items it measures (a reply built by measuring the whole list again and again
    measures quadratically many); past ``budget`` it stops the test instead of running for minutes."""

    def __init__(self, wire, budget: int):
        self.wire, self.budget, self.items = wire, budget, 0

    def size_of(self, message, path, value):
        data = value["fields"]["data"] if isinstance(value, dict) and value.get("abbrev") == "HistoricData" else value
        self.items += len(data) if isinstance(data, list) else 1
        if self.items > self.budget:
            raise AssertionError(f"the reply measured over {self.budget} items")
        return self.wire.size_of(message, path, value)

    def __getattr__(self, name):
        return getattr(self.wire, name)


@pytest.fixture()
def node(suite):
    node = ReferenceNode(suite.defs, suite.behaviour, edition="imc-5.4.30", address=NODE, system=NODE_ID)
    announce = {"sys_name": "console", "sys_type": 0, "owner": 0xFFFF, "lat": 0.0, "lon": 0.0, "height": 0.0,
                "services": "imc+udp://127.0.0.1:7000/"}
    node.receive(0.0, frame(suite.defs, "Announce", announce), CONSOLE)
    node.due(0.0)
    return node


def flood(node, defs, samples: list[dict]) -> None:
    for start in range(0, len(samples), PER_DATAGRAM):
        data = {"base_lat": 0.0, "base_lon": 0.0, "base_time": 0.0, "data": samples[start:start + PER_DATAGRAM]}
        node.receive(1.0, frame(defs, "HistoricData", data), CONSOLE)


def query(node, defs, max_size: int) -> tuple[bytes, list[dict]]:
    """The reply to a QUERY of ``max_size`` bytes: its frame and the items it holds."""
    node.receive(2.0, frame(defs, "HistoricDataQuery", {"req_id": 7, "type": 1, "max_size": max_size, "data": None}),
                 CONSOLE)
    replies = [f for _, f in node.due(3.0) if codec.decode(defs, f)["abbrev"] == "HistoricDataQuery"]
    assert len(replies) == 1
    data = codec.decode(defs, replies[0])["fields"]["data"]
    return replies[0], data["fields"]["data"] if data else []


def test_a_query_over_a_full_datagram_of_samples_is_answered_in_one_pass_within_a_datagram(node, suite):
    flood(node, suite.defs, [sample(0, i) for i in range(2 * PER_DATAGRAM)])
    node.wire = Measured(node.wire, budget=3 * 2 * PER_DATAGRAM)
    reply, items = query(node, suite.defs, 65535)
    assert len(reply) <= DATAGRAM  # sendable: the largest max_size is bounded by what a datagram holds
    assert [i["fields"]["x"] for i in items] == list(range(len(items))) and len(items) > 4000  # earliest first
    payload = len(reply) - codec.HEADER_SIZE - 2 - 5
    small, small_items = query(node, suite.defs, 1000)
    assert len(small) - codec.HEADER_SIZE - 2 - 5 <= 1000 < payload and 0 < len(small_items) < len(items)


def test_a_flood_of_68000_samples_leaves_the_store_bounded_and_the_highest_priority_kept(node, suite):
    flood(node, suite.defs, [sample(5, i) for i in range(100)])  # first, of a high priority
    flood(node, suite.defs, [sample(0, i % 32768) for i in range(68_000)])
    assert len(node.kept) <= KEPT_MAX + KEPT_SLACK
    flood(node, suite.defs, [sample(9, i) for i in range(10)])  # last, of the highest
    assert len(node.kept) <= KEPT_MAX + KEPT_SLACK
    node.wire = Measured(node.wire, budget=3 * (KEPT_MAX + KEPT_SLACK))
    reply, items = query(node, suite.defs, 65535)
    assert len(reply) <= DATAGRAM
    assert [(i["fields"]["priority"], i["fields"]["x"]) for i in items[:110]] == \
        [(9, x) for x in range(10)] + [(5, x) for x in range(100)]
    assert [i["fields"]["x"] for i in items[110:]] == list(range(len(items) - 110))  # then the earliest of the rest
