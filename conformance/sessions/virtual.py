"""An in-memory link on virtual time: the session talks to a sans-IO node object in the same process, and the
clock jumps from event to event, so a scenario set that takes minutes of protocol time runs in milliseconds
and the same inputs always give the same run. For tests and the benchmark; the node must offer
``receive(t, data, source)``, ``due(t) -> [(address, data)]`` and ``deadline``. ``capacity`` bounds the
session's receive queue as a kernel's buffer does: what arrives while it is full is dropped and counted."""

from __future__ import annotations

from collections import deque


class VirtualLink:
    def __init__(self, node, node_address: tuple, own_address: tuple, epoch0: float = 1_700_000_000.0,
                 start: float = 0.0, capacity: int | None = None):
        self.node, self.node_address, self.own_address = node, node_address, own_address
        self.t, self.epoch0, self.capacity = start, epoch0, capacity
        self.inbox: deque = deque()
        self.lost = 0  # datagrams dropped because the queue was full
        self.sent: list[bytes] = []  # everything the session sent, in order (tests read it)

    def now(self) -> float:
        return self.t

    def epoch(self, t: float) -> float:
        return self.epoch0 + t

    def send(self, data: bytes, address=None) -> str | None:
        self.sent.append(bytes(data))
        if address is None or tuple(address) == self.node_address:
            self.node.receive(self.t, bytes(data), self.own_address)
        return None

    @property
    def target(self) -> tuple:
        return self.node_address

    @property
    def address(self) -> tuple:
        return self.own_address

    def receive(self, until: float) -> tuple[float, bytes, tuple] | None:
        while not self.inbox:
            deadline = self.node.deadline
            if deadline is None or deadline > until:
                self.t = max(self.t, until)
                return None
            self.t = max(self.t, deadline)
            for address, data in self.node.due(self.t):
                if tuple(address) != self.own_address:
                    continue
                if self.capacity is not None and len(self.inbox) >= self.capacity:
                    self.lost += 1
                else:
                    self.inbox.append((self.t, data, self.node_address))
        return self.inbox.popleft()

    def drops(self, poll: bool = False) -> int:
        return self.lost

    def close(self) -> None:
        pass
