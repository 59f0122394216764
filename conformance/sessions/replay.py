"""A recorded run played back: the session's link is a recording (a pcapng ``run --pcap`` wrote) on virtual
time, so the scenario engine meets what the target sent when it sent it, and judges it again. Sends go nowhere;
each is checked against the recording, and where the replay departs from it a note says so."""

from __future__ import annotations

from dataclasses import dataclass

from ..capture.recording import OWN, RECEIVED


@dataclass(frozen=True)
class Recorded:
    """One datagram of the recording: ``t`` seconds after its first, between ``src`` and ``dst``."""

    t: float
    src: tuple
    dst: tuple
    data: bytes
    comment: str


class RecordingEnds(KeyboardInterrupt):
    """The recording of a run that did not end (interrupted, or the file cut) has no more: the replay stops as
    an interrupted run does, keeping the cases that finished within the recording."""


class ReplayLink:
    """The transport: what the target sent, delivered at its recorded time; the session's own sends checked.
    ``complete``: the recorded run ended; otherwise nothing is known past its last datagram."""

    def __init__(self, recording: list[Recorded], target: tuple, address: tuple, epoch0: float, complete: bool):
        self.target, self.address, self.epoch0, self.complete = target, address, epoch0, complete
        self.end = recording[-1].t if recording else 0.0
        self.incoming = [r for r in recording if r.comment == RECEIVED]
        self.expected = [r for r in recording if r.comment not in (RECEIVED, OWN)]
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
        if not self.complete and until > self.end:
            raise RecordingEnds
        self.t = max(self.t, until)
        return None

    def record(self, epoch: float, src: tuple, dst: tuple, data: bytes, comment: str) -> None:
        """The replayed session's datagram: a scenario's send is compared with the recording's next one."""
        if comment in (RECEIVED, OWN):
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
