"""The relay between a console and a vehicle, sans-IO: the caller says what time it is, hands over each datagram a
side sent (``inbound``) and sends what ``due`` returns. Each direction goes through its own ``Link``; each side is
judged as a watcher at that side would judge it (a capture judge fed what the side sent and what it received
intact), so that a responder is judged on the requests that reached it, never on those the relay lost. What the
link failed to deliver tells each side's judge not to judge the absences it may have caused (a request, or the
reply it awaited): those are INCONCLUSIVE, never FAIL; an answer that arrived is judged whatever was lost around it.
The time the relay added to a request's way and its reply's widens the requester's view of the bound; a copy the relay
made of a request tells both sides' judges that its addressee may answer twice. Each case names the side it blames
(``by-<side>``). What a direction holds in flight is bounded in bytes (IN_FLIGHT_LIMIT): beyond it a datagram is a
loss of the link, counted."""

from __future__ import annotations

import heapq
import ipaddress
import itertools
from collections import Counter
from dataclasses import dataclass

from ..capture.datagrams import Datagram
from ..capture.findings import Watched
from ..core.results import MessageResult, RunResult, message_verdict
from .impairment import Link
from .resend import ResendWatch

SIDES = ("console", "vehicle")
OTHER = {"console": "vehicle", "vehicle": "console"}
IN_FLIGHT_LIMIT = 32 << 20  # bytes one direction holds on the way; a datagram beyond is lost (a full buffer)
BLAME = "/by-"  # how a finding's case names the side it blames until ``side_id`` files it
LOOPBACK = ipaddress.ip_network("127.0.0.0/8")
LOOPBACK_NOT_HOSTS = {LOOPBACK.broadcast_address: "broadcast", LOOPBACK.network_address: "network"}


def loopback_host(address: str) -> bool:
    """Whether ``address`` (an IP, text) is one host's on loopback: never another host's, a group's or the loopback
    network's broadcast (the relay talks to nothing else)."""
    try:
        ip = ipaddress.ip_address(address.split("%")[0])
    except ValueError:
        return False
    return ip.is_loopback and ip not in LOOPBACK_NOT_HOSTS


@dataclass(slots=True)
class Carried(Datagram):
    """A datagram a side sent through the relay; ``added``: the seconds the relay added to its way and (at most, by
    the link's usual delay) to its reply's, which its sender could not see (passive.py widens the sender's bound)."""

    added: float = 0.0


class _Blamed:
    """A side's exchange tracker whose findings name the side they blame: an exchange's findings blame the
    addressee of its request (the side that did not send it)."""

    def __init__(self, tracker, sender):
        self.tracker, self.sender = tracker, sender

    def __getattr__(self, name):
        return getattr(self.tracker, name)

    def _named(self, findings: list) -> list:
        for f in findings:
            asker = self.sender(f.asker)
            if asker is not None:
                f.case += f"{BLAME}{OTHER[asker]}"
        return findings

    def observe(self, w):
        return self._named(self.tracker.observe(w))

    def due(self, now: float):
        return self._named(self.tracker.due(now))

    def finish(self, end: float):
        return self._named(self.tracker.finish(end))

    def split(self, why: str):
        findings, count = self.tracker.split(why)
        return self._named(findings), count


class Relay:
    """``judges``: a capture judge per side; ``links``: per sending side, the ``Link`` its datagrams go through;
    ``facing``: per side, the relay's own address that side talks to; ``endpoints``: per side, the side's address
    (None: learned from its first datagram); ``rewrite(data, facing)``: the suite's change to a datagram so that
    replies come back through the relay (an announced address), or None; ``resend``: the (ambiguity, clause) under
    which a requester's resending is recorded, or None; ``introductions``: the messages by which a system makes
    itself known to a peer (one lost, the peer may rightly ignore the system until the next arrives);
    ``record(t, src, dst, data, comment)``: the recording; ``reply_to(data)``: the address a datagram asks to be
    answered at (a side the relay learns, the console, is then sent to there, not to where it sent from)."""

    def __init__(self, judges: dict, links: dict[str, Link], facing: dict[str, tuple], endpoints: dict[str, tuple | None],
                 rewrite=None, resend: tuple[str, str] | None = None, introductions=frozenset(), record=None,
                 reply_to=None):
        self.judges, self.links, self.facing, self.endpoints = judges, links, facing, dict(endpoints)
        self.reply_to = reply_to
        self.sources: dict[str, tuple | None] = {side: None for side in SIDES}  # the first address each side sent from
        for judge in judges.values():
            judge.tracker = _Blamed(judge.tracker, self.sender)
        self.rules = judges[SIDES[0]].rules  # the judges' rules decode the fields their exchanges watch
        self.rewrite, self.record, self.introductions = rewrite, record, introductions
        self.unknown: dict[tuple, list] = {}  # (receiving side, system) -> the times since its introduction was lost
        self.introduced: set[tuple] = set()  # (receiving side, system) of every introduction delivered
        self.resend = {side: ResendWatch(judges[side].tracker.by_request, resend) for side in SIDES} if resend else None
        self.queue: list = []
        self.order = itertools.count()
        self.number = itertools.count(1)
        self.systems: dict[str, set[int]] = {side: set() for side in SIDES}  # the ids each side's frames carry
        self.counts: dict[str, Counter] = {side: Counter() for side in SIDES}  # per sending side
        self.in_flight = {side: 0 for side in SIDES}  # bytes on the way, per sending side
        self.rewritten = 0

    def sender(self, datagram) -> str | None:
        """The side that sent a datagram a judge was given (to the relay's socket facing it), or None."""
        if datagram is None:
            return None
        for side in SIDES:
            if (datagram.dst, datagram.dport) == self.facing[side]:
                return side
            if (datagram.src, datagram.sport) == self.facing[side]:
                return OTHER[side]
        return None

    @property
    def deadline(self) -> float | None:
        return self.queue[0][0] if self.queue else None

    def accepts(self, side: str, source: tuple, data: bytes) -> bool:
        """Whether a datagram that came from ``source`` on the socket facing ``side`` is that side's: the vehicle's
        from its address only; the console's from the first address that spoke, or from any other whose frame
        speaks as one of the console's systems (a node may send each datagram from a socket of its own)."""
        first = self.sources[side]
        if first is None or first == source:
            return side == "console" or source == self.endpoints[side]
        if side == "vehicle":
            return False
        frame = self.rules.frame(data)
        return frame is not None and frame.src is not None and frame.src in self.systems[side]

    def inbound(self, t: float, side: str, data: bytes, source: tuple) -> None:
        """A datagram ``side`` sent at ``t`` from ``source``."""
        if self.sources[side] is None:
            self.sources[side] = source
        if self.endpoints[side] is None or (side == "console" and self.endpoints[side] == self.sources[side]):
            asked = self.reply_to(data) if self.reply_to is not None else None
            if asked is not None and not loopback_host(asked[0]):  # whatever a suite's hook reads from a frame
                asked = None
            self.endpoints[side] = asked or self.endpoints[side] or source
        origin, relay, to = source, self.facing[side], OTHER[side]
        self.counts[side]["sent"] += 1
        if self.record:
            self.record(t, origin, relay, data, f"{side} sent")
        frame = self.rules.frame(data)
        if frame is not None and frame.src is not None:
            self.systems[side].add(frame.src)
        carried = data
        if self.rewrite is not None:
            changed = self.rewrite(data, self.facing[to])
            if changed is not None:
                carried, self.rewritten = changed, self.rewritten + 1
        fate = self.links[side].carry(t, carried)
        size = len(carried) * len(fate.copies)
        if fate.dropped is None and self.in_flight[side] + size > IN_FLIGHT_LIMIT:
            fate.dropped = f"over the relay's {IN_FLIGHT_LIMIT >> 20} MiB in flight (a full buffer)"
        added = fate.copies[0][0] - t + self.links[to].impairment.usual if fate.dropped is None else 0.0
        sent = Carried(next(self.number), t, origin[0], origin[1], relay[0], relay[1], data, added=added)
        self.judges[side].received(sent)
        if self.resend and frame is not None and frame.group is not None:
            for finding in self.resend[side].sent(sent, frame.group, frame):
                self._found(side, finding)
        if fate.dropped is not None:
            self.counts[side][fate.dropped] += 1
            self._undelivered(sent, side, frame, fate.dropped)
            return
        self.in_flight[side] += size
        if frame is not None and frame.group in self.introductions and frame.src is not None \
                and (to, frame.src) not in self.introduced:  # a request overtaking it may find the system unknown
            self._unknown(to, frame.src, t, f"the relay had not yet delivered an introduction of system "
                                            f"{frame.src:#06x} to the {to} (datagram {sent.number})")
        for when, copy, note in fate.copies:
            heapq.heappush(self.queue, (when, next(self.order), to, copy, note, sent, frame))
            for what in filter(None, note.split(", ")):
                self.counts[side]["held back" if what.startswith("held") else "with a byte changed"
                                  if what.startswith("byte") else what] += 1
        if len(fate.copies) > 1 and frame is not None and frame.fields is not None:  # its sender's view of the copy
            self.judges[side].tracker.again(Watched(sent.number, t, frame.group, frame.fields, frame.src, frame.dst,
                                                    sent))

    def due(self, t: float, send=None) -> list[tuple[str, bytes]]:
        """The datagrams to deliver by ``t``: (the side they go to, their bytes). ``send(side, data)``: sends one,
        False when it could not (then it was not delivered); None: the caller sends what is returned."""
        out = []
        while self.queue and self.queue[0][0] <= t:
            when, _, to, data, note, sent, frame = heapq.heappop(self.queue)
            origin = OTHER[to]
            self.in_flight[origin] -= len(data)
            relay, endpoint = self.facing[to], self.endpoints[to]
            if endpoint is None:  # the console has not spoken yet: nowhere to send
                self.counts[origin]["undeliverable (the console had not spoken yet)"] += 1
                self._undelivered(sent, origin, frame, "the console had not spoken yet", until=when)
                continue
            if send is not None and not send(to, data):
                self.counts[origin]["could not be sent (the receiver's port closed, or buffers full)"] += 1
                self._undelivered(sent, origin, frame, "could not be sent", until=when)
                continue
            self.counts[origin]["delivered"] += 1
            if self.record:
                self.record(when, relay, endpoint, data, f"{to} received" + (f" ({note})" if note else ""))
            if "byte" in note:  # changed on the way: the receiver sees no frame of the sender's
                self._undelivered(sent, origin, frame, "corrupted", until=when)
                out.append((to, data))
                continue
            late = when - sent.time - self.links[origin].impairment.usual
            if late > 1e-9:  # held beyond the link's usual delay: an absence meanwhile is the relay's
                self.judges[to].tracker.lost(sent.time, when, f"the relay held datagram {sent.number} from the "
                                             f"{origin} {when - sent.time:.3g} s", self._systems(to, frame))
            self.judges[to].received(Datagram(next(self.number), when, relay[0], relay[1], endpoint[0], endpoint[1],
                                              data), frames=False)
            if frame is not None and frame.group in self.introductions:
                self._introduced(to, frame.src, when)
            out.append((to, data))
        return out

    def _systems(self, side: str, frame) -> frozenset | None:
        """The systems of ``side`` a frame to it is addressed to (a destination naming no system in particular
        stands for all of them); None: any."""
        tracker = self.judges[side].tracker
        anyone = (tracker.anyone, tracker.nobody)
        dst = ({frame.dst} if frame is not None and frame.dst is not None and frame.dst not in anyone
               else set(self.systems[side]) or None)
        return None if dst is None else frozenset(dst)

    def _found(self, side: str, finding) -> None:
        """A resend finding: it blames the requester."""
        finding.case += f"{BLAME}{side}"
        self.judges[side].found(finding)

    def _undelivered(self, sent: Datagram, side: str, frame, why: str, until: float | None = None) -> None:
        """The datagram ``side`` sent (number N) did not reach the other side intact: the absences it may have caused
        are not judged, in each side's view, for the systems whose requests they are."""
        to, t = OTHER[side], sent.time
        src = {frame.src} if frame is not None and frame.src is not None else set(self.systems[side]) or None
        why = f"the relay did not deliver datagram {sent.number} from the {side} ({why})"
        self.judges[side].tracker.withdraw(sent.number, why)
        self.judges[side].tracker.lost(t, until or t, why, None if src is None else frozenset(src))
        self.judges[to].tracker.lost(t, until or t, why, self._systems(to, frame))
        if frame is not None and frame.group in self.introductions and frame.src is not None:
            self._unknown(to, frame.src, t, f"the relay lost an introduction of system {frame.src:#06x} to the {to} "
                                            f"(datagram {sent.number})")
        if self.resend and frame is not None and frame.group is not None:
            self.resend[side].undelivered(sent, frame.group, frame)

    def _unknown(self, side: str, system: int, t: float, why: str) -> None:
        """From ``t``, ``system`` may be unknown to ``side`` (``why``), until an introduction of it reaches ``side``:
        the requests ``system`` sends meanwhile, which ``side`` may rightly ignore, are not judged, in both views."""
        if (side, system) not in self.unknown:
            self.unknown[(side, system)] = [self.judges[each].tracker.lost(t, float("inf"), why, frozenset([system]))
                                            for each in SIDES]

    def _introduced(self, side: str, system: int, t: float) -> None:
        """``side`` got an introduction of ``system`` at ``t``: the requests of ``system`` that ``side`` ignored since
        the one lost before it are not judged (an answer ``side`` sent is judged all the same); those after are."""
        self.introduced.add((side, system))
        for lost in self.unknown.pop((side, system), ()):  # in both sides' views
            lost[1] = t

    def finish(self, t: float) -> None:
        """Judge what the end of the relay at ``t`` decides: the resends whose window ended."""
        for side in SIDES if self.resend else ():
            for finding in self.resend[side].finish(t):
                self._found(side, finding)

    def notes(self) -> list[str]:
        """What each direction carried and what befell it, and the systems each side spoke as."""
        out = []
        on_the_way = Counter(OTHER[entry[2]] for entry in self.queue)
        for side in SIDES:
            counts = self.counts[side]
            if on_the_way[side]:
                counts["still on the way when the relay stopped"] = on_the_way[side]
            befell = ", ".join(f"{n} {what}" for what, n in sorted(counts.items()) if what not in ("sent", "delivered"))
            systems = ", ".join(f"{s:#06x}" for s in sorted(self.systems[side])) or "none seen"
            out.append(f"{side} to {OTHER[side]}: {counts['sent']} datagrams sent, {counts['delivered']} delivered"
                       + (f"; {befell}" if befell else "") + f"; the {side}'s systems: {systems}")
        unread = sum(watch.unread for watch in self.resend.values()) if self.resend else 0
        if unread:
            out.append(f"{unread} lost requests were not watched for a resend (too many awaited one at once)")
        if self.rewritten:
            out.append(f"{self.rewritten} datagrams had the address they announce changed to the relay's, so that "
                       "replies come back through it")
        return out


def side_id(case_id: str, side: str) -> str:
    """A capture case's id as the relay files it: ``<suite>/<group>/relay/<side>/by-<blamed side>/<case>``, under the
    side whose watcher judged it, naming the side it blames (a frame: the side that sent it, the only one whose
    frames that side's judge judges)."""
    head, sep, tail = case_id.partition("/capture/")
    if not sep:
        return case_id
    tail, _, blamed = tail.partition(BLAME)
    return f"{head}/relay/{side}/by-{blamed or side}/{tail}"


def merged(results: dict[str, RunResult], strict: bool, judged: tuple[str, ...] = SIDES) -> RunResult:
    """One result of both sides' results: each message's cases from both, filed under each side; only the cases that
    blame a side in ``judged`` (a vehicle that sent nothing is judged on nothing)."""
    first = results[SIDES[0]]
    cases: dict[str, list] = {}
    keys: dict[str, str] = {}
    for side in SIDES:
        for message in results[side].messages:
            keys.setdefault(message.name, message.key)
            for case in message.cases:
                case.id = side_id(case.id, side)
                if any(f"/relay/{side}/by-{blamed}/" in case.id for blamed in judged):
                    cases.setdefault(message.name, []).append(case)
    messages = [MessageResult(name, keys[name], message_verdict(group, strict), group) for name, group in cases.items()]
    notes = [f"{side}: {note}" for side in SIDES for note in results[side].notes]
    return RunResult(first.suite, first.title, first.edition, first.implementation, first.adapter, strict, first.started,
                     first.duration, messages, notes=notes, complete=all(r.complete for r in results.values()))
