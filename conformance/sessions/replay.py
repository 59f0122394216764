"""A recorded run played back: the session's link is a recording (a pcapng ``run --pcap`` wrote) on virtual
time, so the scenario engine meets what the target sent when it sent it, and judges it again. Sends go nowhere;
each is checked against the recording, and where the replay departs from it a note says so."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Recorded:
    """One datagram of the recording: ``t`` seconds after its first, between ``src`` and ``dst``."""

    t: float
    src: tuple
    dst: tuple
    data: bytes
    comment: str


class ReplayLink:
    """The transport: what the target sent, delivered at its recorded time; the session's own sends checked."""

    def __init__(self, recording: list[Recorded], target: tuple, address: tuple, epoch0: float):
        self.target, self.address, self.epoch0 = target, address, epoch0
        self.incoming = [r for r in recording if r.comment == "received"]
        self.expected = [r for r in recording if r.comment not in ("received", "the session's own")]
        self.t, self.next, self.sent = 0.0, 0, 0
        self.departures: list[str] = []

    def now(self) -> float:
        return self.t

    def epoch(self, t: float) -> float:
        return self.epoch0 + t

    def send(self, data: bytes, address=None) -> str | None:
        return None

    def receive(self, until: float) -> tuple[float, bytes, tuple] | None:
        if self.next < len(self.incoming) and self.incoming[self.next].t <= until:
            r = self.incoming[self.next]
            self.next += 1
            self.t = max(self.t, r.t)
            return self.t, r.data, r.src
        self.t = max(self.t, until)
        return None

    def record(self, epoch: float, src: tuple, dst: tuple, data: bytes, comment: str) -> None:
        """The replayed session's datagram: a scenario's send is compared with the recording's next one."""
        if comment in ("received", "the session's own"):
            return
        if self.sent < len(self.expected):
            was = self.expected[self.sent]
            if was.comment != comment and len(self.departures) < 5:
                self.departures.append(f"the replay sent {comment} where the recording has {was.comment} "
                                       f"(at {was.t:.3f} s)")
        elif len(self.departures) < 5:
            self.departures.append(f"the replay sent {comment}, which the recording does not have")
        self.sent += 1

    @property
    def notes(self) -> list[str]:
        out = [f"replayed from the recording: {len(self.incoming)} datagrams from the target"]
        out += self.departures
        if self.sent < len(self.expected):
            out.append(f"the recording has {len(self.expected) - self.sent} scenario sends the replay did not make")
        return out

    def close(self) -> None:
        pass
