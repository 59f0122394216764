"""The relay between a console and a vehicle, sans-IO: the caller says what time it is, hands over each datagram a
side sent (``inbound``) and sends what ``due`` returns. Each direction goes through its own ``Link``; each side is
judged as a watcher at that side would judge it (a capture judge fed what the side sent and what it received
intact), so that a responder is judged on the requests that reached it, never on those the relay lost. What the
link failed to deliver tells each side's judge not to judge the requests it may have cost (a request, or the reply
it awaited): those are INCONCLUSIVE, never FAIL."""

from __future__ import annotations

import heapq
import itertools
from collections import Counter

from ..capture.datagrams import Datagram
from ..core.results import MessageResult, RunResult, message_verdict
from .impairment import Link
from .resend import ResendWatch

SIDES = ("console", "vehicle")
OTHER = {"console": "vehicle", "vehicle": "console"}


class Relay:
    """``judges``: a capture judge per side; ``links``: per sending side, the ``Link`` its datagrams go through;
    ``facing``: per side, the relay's own address that side talks to; ``endpoints``: per side, the side's address
    (None: learned from its first datagram); ``rewrite(data, facing)``: the suite's change to a datagram so that
    replies come back through the relay (an announced address), or None; ``resend``: the (ambiguity, clause) under
    which a requester's resending is recorded, or None; ``introductions``: the messages by which a system makes
    itself known to a peer (one lost, the peer may rightly ignore the system until the next arrives);
    ``record(t, src, dst, data, comment)``: the recording."""

    def __init__(self, judges: dict, links: dict[str, Link], facing: dict[str, tuple], endpoints: dict[str, tuple | None],
                 rewrite=None, resend: tuple[str, str] | None = None, introductions=frozenset(), record=None):
        self.judges, self.links, self.facing, self.endpoints = judges, links, facing, dict(endpoints)
        self.rules = judges[SIDES[0]].rules  # the judges' rules decode the fields their exchanges watch
        self.rewrite, self.record, self.introductions = rewrite, record, introductions
        self.unknown: dict[tuple, float] = {}  # (receiving side, system) -> when its introduction was lost
        self.resend = {side: ResendWatch(judges[side].tracker.by_request, resend) for side in SIDES} if resend else None
        self.queue: list = []
        self.order = itertools.count()
        self.number = itertools.count(1)
        self.systems: dict[str, set[int]] = {side: set() for side in SIDES}  # the ids each side's frames carry
        self.counts: dict[str, Counter] = {side: Counter() for side in SIDES}  # per sending side
        self.rewritten = 0

    @property
    def deadline(self) -> float | None:
        return self.queue[0][0] if self.queue else None

    def inbound(self, t: float, side: str, data: bytes, source: tuple) -> None:
        """A datagram ``side`` sent at ``t`` from ``source``."""
        if self.endpoints[side] is None:
            self.endpoints[side] = source
        origin, relay = source, self.facing[side]
        self.counts[side]["sent"] += 1
        sent = Datagram(next(self.number), t, origin[0], origin[1], relay[0], relay[1], data)
        self.judges[side].received(sent)
        if self.record:
            self.record(t, origin, relay, data, f"{side} sent")
        frame = self.rules.frame(data)
        if frame is not None and frame.src is not None:
            self.systems[side].add(frame.src)
        if self.resend and frame is not None and frame.group is not None:
            for finding in self.resend[side].sent(sent, frame.group, frame):
                self.judges[side].found(finding)
        to = OTHER[side]
        if self.rewrite is not None:
            changed = self.rewrite(data, self.facing[to])
            if changed is not None:
                data, self.rewritten = changed, self.rewritten + 1
        fate = self.links[side].carry(t, data)
        if fate.dropped is not None:
            self.counts[side][fate.dropped] += 1
            self._undelivered(sent, side, frame, fate.dropped)
            return
        for when, copy, note in fate.copies:
            heapq.heappush(self.queue, (when, next(self.order), to, copy, note, sent, frame))
            for what in filter(None, note.split(", ")):
                self.counts[side]["held back" if what.startswith("held") else "with a byte changed"
                                  if what.startswith("byte") else what] += 1

    def due(self, t: float) -> list[tuple[str, bytes]]:
        """The datagrams to deliver by ``t``: (the side they go to, their bytes)."""
        out = []
        while self.queue and self.queue[0][0] <= t:
            when, _, to, data, note, sent, frame = heapq.heappop(self.queue)
            relay, endpoint = self.facing[to], self.endpoints[to]
            if endpoint is None:  # the console has not spoken yet: nowhere to send
                self.counts[OTHER[to]]["undeliverable (the console had not spoken yet)"] += 1
                self._undelivered(sent, OTHER[to], frame, "the console had not spoken yet", until=when)
                continue
            self.counts[OTHER[to]]["delivered"] += 1
            if self.record:
                self.record(when, relay, endpoint, data, f"{to} received" + (f" ({note})" if note else ""))
            if "byte" in note:  # changed on the way: the receiver sees no frame of the sender's
                self._undelivered(sent, OTHER[to], frame, "corrupted", until=when)
            else:
                self.judges[to].received(Datagram(next(self.number), when, relay[0], relay[1], endpoint[0],
                                                  endpoint[1], data))
                if frame is not None and frame.group in self.introductions:
                    self._introduced(to, frame.src, when)
            out.append((to, data))
        return out

    def _undelivered(self, sent: Datagram, side: str, frame, why: str, until: float | None = None) -> None:
        """The datagram ``side`` sent did not reach the other side intact: the requests it may have cost are not
        judged, in each side's view, for the systems whose requests they are."""
        to, t = OTHER[side], sent.time
        src = {frame.src} if frame is not None and frame.src is not None else set(self.systems[side]) or None
        tracker = self.judges[to].tracker  # a destination naming no system in particular stands for all of them
        anyone = (getattr(tracker, "anyone", None), getattr(tracker, "nobody", None))
        dst = ({frame.dst} if frame is not None and frame.dst is not None and frame.dst not in anyone
               else set(self.systems[to]) or None)
        why = f"the relay did not deliver a datagram from the {side} ({why})"
        self.judges[side].tracker.lost(t, until or t, why, None if src is None else frozenset(src))
        self.judges[to].tracker.lost(t, until or t, why, None if dst is None else frozenset(dst))
        if frame is not None and frame.group in self.introductions and frame.src is not None:
            self.unknown.setdefault((to, frame.src), t)
        if self.resend and frame is not None and frame.group is not None:
            self.resend[side].undelivered(sent, frame.group, frame)

    def _introduced(self, side: str, system: int, t: float) -> None:
        """``side`` got an introduction of ``system`` at ``t``: since the one lost before it, the requests of
        ``system`` that ``side`` ignored are not judged."""
        since = self.unknown.pop((side, system), None)
        if since is not None:
            self.judges[side].tracker.lost(since, t, f"the relay lost an introduction of system {system:#06x} to the "
                                                     f"{side}", frozenset([system]))

    def finish(self, t: float) -> None:
        """Judge what the end of the relay decides: the resends, the introductions never made again."""
        for side, system in list(self.unknown):
            self._introduced(side, system, float("inf"))
        for side in SIDES if self.resend else ():
            for finding in self.resend[side].expire(float("inf")):
                self.judges[side].found(finding)

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
        if self.rewritten:
            out.append(f"{self.rewritten} datagrams had the address they announce changed to the relay's, so that "
                       "replies come back through it")
        return out


def side_id(case_id: str, side: str) -> str:
    """A capture case's id as the relay files it: ``<suite>/<group>/relay/<side>/<case>``."""
    head, sep, tail = case_id.partition("/capture/")
    return f"{head}/relay/{side}/{tail}" if sep else case_id


def merged(results: dict[str, RunResult], strict: bool) -> RunResult:
    """One result of both sides' results: each message's cases from both, filed under each side."""
    first = results[SIDES[0]]
    cases: dict[str, list] = {}
    keys: dict[str, str] = {}
    for side in SIDES:
        for message in results[side].messages:
            keys.setdefault(message.name, message.key)
            for case in message.cases:
                case.id = side_id(case.id, side)
                cases.setdefault(message.name, []).append(case)
    messages = [MessageResult(name, keys[name], message_verdict(group, strict), group) for name, group in cases.items()]
    notes = [f"{side}: {note}" for side in SIDES for note in results[side].notes]
    return RunResult(first.suite, first.title, first.edition, first.implementation, first.adapter, strict, first.started,
                     first.duration, messages, notes=notes, complete=all(r.complete for r in results.values()))
