"""How the session behaves on an IMC link, sans-IO: a well-mannered peer, because real nodes ignore
unannounced sources (imc-wire.md, "IMC over UDP"). It announces its ``imc+udp://IP:PORT/`` service to the
target and to the target host's discovery ports 30100-30104 every 10 s, heart-beats to the target at 1 Hz, learns the
node's id from its first valid frame (unless given), and says the target is ready once a valid frame from
it arrived (at once when its id is given: the seeds do not make Heartbeat periodic, erratum E7). It also announces
a second system (``other``, named ``<name>-2``, on the same socket), the second client that scenarios about two
clients on the link and about forwarding speak as; and a third (``late``, named ``<name>-3``) only once a scenario has
spoken as it: a system that appears on the link during a run (a recipient that comes back into reach).

It tells when the node is gone (liveness): a node that has been sending Heartbeats and then sends nothing at all for
five times its longest gap between them (at least 5 s) has stopped, and the scenarios waiting on it need not each
wait out its bound (the session decides them then, untested). A node that never heart-beats is never taken for gone.

It also says which frames are for the session: replies are matched on the header, not on the socket they
arrive at, because a node like DUNE sends what its UDP transport lists to every contact. Frames the session
itself sent (echoed back) and frames addressed to another system (the node's own internal messages) are not
for it; frames to the session's id, to anyone (0xFFFF) or to 0 (DUNE addresses Announce so) are. A frame sent
with the session's id is never the node's, and an Announce with its id for another service shows another system
using that id (two runs with the same --src talking to one node take each other's replies)."""

from __future__ import annotations

from .definitions import Definitions
from . import codec
from .values import text_bytes

DISCOVERY_PORTS = range(30100, 30105)
DEFAULT_SYSTEM = 0x4CF0  # the session's IMC id in tests and in recordings made before ids were chosen per run
SYSTEMS = range(0x4C01, 0x4CFF)  # the ids a run chooses from: outside DUNE's and Neptus' usual ranges
ANNOUNCE_EVERY, HEARTBEAT_EVERY = 10.0, 1.0
GONE_AFTER_BEATS, GONE_AFTER_GAPS, GONE_AT_LEAST = 3, 5.0, 5.0  # liveness: Heartbeats seen first; silence, in gaps


def session_system(src: int | None, first_unique: int | None) -> int:
    """The session's IMC id: ``--src`` if given, else one of ``SYSTEMS`` chosen by the run's first unique number
    (random per run, and recorded, so two runs at once rarely share an id and a replay finds the same one)."""
    if src is not None:
        return src
    return DEFAULT_SYSTEM if first_unique is None else SYSTEMS[first_unique % len(SYSTEMS)]


def other_system(system: int, avoid: int | None = None) -> int:
    """The session's second system (a second client on the link): the next id of ``SYSTEMS`` after the session's,
    or the next id after a given one; never the node's (``avoid``), 0 or 0xFFFF."""
    candidate = system
    while True:
        candidate = SYSTEMS[(SYSTEMS.index(candidate) + 1) % len(SYSTEMS)] if candidate in SYSTEMS else (candidate + 1) % 0xFFFF
        if candidate not in (0, system, avoid):
            return candidate


class ImcPeer:
    def __init__(self, defs: Definitions, *, system: int, node: int | None, service: str, host: str, epoch,
                 name: str = "imc-conformance", chosen: bool = False):
        """``service``: the session's own imc+udp URL; ``host``: the target's host (for discovery ports);
        ``epoch(t)``: seconds since 1970 at clock time t; ``chosen``: the id was chosen for the run, not given."""
        self.defs, self.system, self.node, self.service, self.host = defs, system, node, service, host
        self.epoch, self.name = epoch, name
        self.other = other_system(system, node)  # the second client: announced under its own name, same socket
        self.stranger = other_system(self.other, node)  # never announced: a sender the node has not heard of
        self.late = other_system(self.stranger, node)  # announced once a step has spoken as it (it appears)
        self.appeared = False
        self.notes = [f"the session's IMC id: {system:#06x} (chosen for this run; --src sets one)"] if chosen else []
        self.given = node is not None
        self.ready = self.given
        self.next_beat = self.next_announce = None
        self.heard_at: float | None = None  # the latest valid frame from the node
        self.beats: list[float] = []  # when its Heartbeats came (the first few, and the latest)
        self.gap = 0.0  # the longest time between two of its Heartbeats

    @property
    def deadline(self) -> float | None:
        return None if self.next_beat is None else min(self.next_beat, self.next_announce)

    def start(self, t: float) -> list[tuple[object, bytes]]:
        """Introduce the session (again, after the target restarted): it is ready once the target shows itself."""
        self.ready = self.given
        self.next_beat, self.next_announce = t + HEARTBEAT_EVERY, t + ANNOUNCE_EVERY
        self.heard_at, self.beats, self.gap = None, [], 0.0  # a restarted node shows its rhythm again
        return self._announcements(t) + [(None, self._heartbeat(t))]

    def due(self, t: float) -> list[tuple[object, bytes]]:
        out = []
        if self.next_beat is not None and t >= self.next_beat:
            self.next_beat = t + HEARTBEAT_EVERY
            out.append((None, self._heartbeat(t)))
        if self.next_announce is not None and t >= self.next_announce:
            self.next_announce = t + ANNOUNCE_EVERY
            out += self._announcements(t)
        return out

    def _announcements(self, t: float) -> list[tuple[object, bytes]]:
        """The Announces of both systems, to the target and to its host's discovery ports (a node that was still
        starting when the last one came, or forgot it, learns of the session from the next: DUNE takes Announces
        only there)."""
        out = []
        announces = [self._announce(t), self._announce(t, second=True)] + ([self._announce(t, third=True)]
                                                                          if self.appeared else [])
        for announce in announces:
            out += [(None, announce)] + [((self.host, port), announce) for port in DISCOVERY_PORTS]
        return out

    def spoke(self, t: float, decoded: dict) -> list[tuple[object, bytes]]:
        """A scenario sent a frame; the first one it sends as ``late`` makes that system appear: it is announced at
        once and every 10 s from then on."""
        if self.appeared or decoded.get("header", {}).get("src") != self.late:
            return []
        self.appeared = True
        announce = self._announce(t, third=True)
        return [(None, announce)] + [((self.host, port), announce) for port in DISCOVERY_PORTS]

    def accepts(self, parsed) -> bool:
        """Whether a frame is for the session (malformed frames are, so the byte-level checks see them)."""
        if parsed.decoded is None:
            return True
        header = parsed.decoded["header"]
        ours = (self.system, self.other) + ((self.late,) if self.appeared else ())
        return not self.own(parsed) and header["dst"] in ours + (0xFFFF, 0)

    def own(self, parsed) -> bool:
        return parsed.decoded is not None and parsed.decoded["header"]["src"] in (self.system, self.other, self.late)

    def impostor(self, parsed) -> str | None:
        if parsed.decoded is None or parsed.message != "Announce" or not self.own(parsed):
            return None
        fields = parsed.decoded["fields"]
        services = text_bytes(fields.get("services", "")).decode("utf-8", "replace")
        if services == self.service:
            return None
        name = text_bytes(fields.get("sys_name", "")).decode("utf-8", "replace")
        system = parsed.decoded["header"]["src"]
        return f"an Announce with the session's id {system:#06x} came from {name!r} at {services[:120]!r}"

    def observe(self, t: float, parsed, from_target: bool) -> None:
        """Learn the node's id, and that it is ready, from its valid frames from the target's own address: not
        from whatever else runs on its host (its discovery traffic: a restarting DUNE announces itself before it
        takes the session's Announce, so its requests would still be dropped)."""
        if parsed.decoded is None or not from_target:
            return
        src = parsed.decoded["header"]["src"]
        if self.node is None and src not in (self.system, self.other, self.late):
            self.node = src
        if src == self.node:
            self.ready = True
            self.heard_at = t
            if parsed.message == "Heartbeat":
                if self.beats:
                    self.gap = max(self.gap, t - self.beats[-1])
                self.beats = self.beats[:GONE_AFTER_BEATS] + [t]

    def gone(self, t: float) -> str | None:
        """Why the node is taken for gone at ``t`` (it heart-beat, then stopped sending anything), or None."""
        if len(self.beats) < GONE_AFTER_BEATS or self.heard_at is None:
            return None
        silent = t - self.heard_at
        if silent < max(GONE_AT_LEAST, GONE_AFTER_GAPS * self.gap):
            return None
        return (f"the node has sent nothing for {silent:.1f} s, after Heartbeats at most {self.gap:.1f} s apart: it is "
                "taken for gone (liveness), and what waited on it was decided then, untested")

    def _announce(self, t: float, second: bool = False, third: bool = False) -> bytes:
        """The Announce of the session's system, or of its second or third: each under its own name (DUNE keeps
        contacts by name) and stamped a millisecond apart (DUNE's discovery drops an Announce from an address whose
        last one carried the same timestamp, whatever system it names)."""
        which = 2 if third else 1 if second else 0
        fields = {"sys_name": f"{self.name}-{which + 1}" if which else self.name, "sys_type": 0, "owner": 0xFFFF,
                  "lat": 0.0, "lon": 0.0, "height": 0.0, "services": self.service}
        return self._frame(t, "Announce", fields, dst=0, src=(self.system, self.other, self.late)[which],
                           later=0.001 * which)

    def _heartbeat(self, t: float) -> bytes:
        return self._frame(t, "Heartbeat", {}, dst=0xFFFF if self.node is None else self.node)

    def _frame(self, t: float, abbrev: str, fields: dict, dst: int, src: int | None = None, later: float = 0.0) -> bytes:
        header = {"timestamp": self.epoch(t) + later, "src": self.system if src is None else src, "src_ent": 0,
                  "dst": dst, "dst_ent": 0xFF}
        return codec.encode(self.defs, {"abbrev": abbrev, "header": header, "fields": fields}, "le")
