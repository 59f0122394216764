"""The exchange rules of a suite (exchanges.json) applied to exchanges the suite only watched (a capture, a
monitor): a request never answered within its bound, a reply echoing another value than its request's, a reply
to another system, a status after a terminal one, a sequence that never ends. Sans-IO. (A reply from another
node than the one asked answers nothing: the request it leaves unanswered is the finding.)

Requests are matched to replies as the scenario engine does, by the exchange's echo fields. A capture can
begin in the middle of an exchange or miss a frame, so a reply that echoes no request seen is set aside; it
is a finding only when a request of its addressee then goes unanswered (the reply did not echo it). Where the
watcher says it lost datagrams (``lost``: the kernel dropped them), a request left unanswered while they were
lost is INCONCLUSIVE: its reply may be among them.
"""

from __future__ import annotations

import bisect
from collections import deque
from dataclasses import dataclass, field

from ...capture.findings import Finding, Watched
from ...core.verdicts import Verdict
from .exchanges import States, resolved, seconds, selected, silence_allowed, states_for, weaker
from .matchers import hashable, same, show
from .wire import Parsed

LEVELS = {"MUST": Verdict.FAIL, "SHOULD": Verdict.NON_STRICT, "INFO": Verdict.IMPL_DEFINED}
STATE_CACHE = 1024  # request values whose reply states are kept resolved
OPEN_LIMIT = 1024  # requests of one exchange followed at once (beyond, the oldest is left unjudged: a flood of
# requests, or a log whose logging system falls silent while others ask on, leaving its clock standing)
UNDONE_KEPT = 64  # earlier messages a silence rule's after selects, kept to tell what a later request asks about
LOSS_GAP = 0.1  # s between two times the frames do not tell all of, below which they are one time


@dataclass
class _Rule:
    """An exchange with the names it uses resolved to the values on the wire for one edition."""

    exchange: dict
    when: dict[str, frozenset]
    reply_when: dict[str, frozenset]
    echoes: list[dict]
    stateful: bool  # its replies carry states (exchanges.json ``state``)
    within: float


@dataclass(slots=True)
class _Open:
    rule: _Rule
    request: Watched
    key: tuple
    deadline: float
    answered: bool = False
    states: States | None = None  # the states of its replies, for this request
    terminal: Watched | None = None
    open_end: str | None = None  # the ambiguity id when its last state is one the seeds leave open
    orphans: list = field(default_factory=list)  # replies to its requester that echoed another value
    unsure: bool = False  # its first reply may have come after its bound (a log's clocks tell no closer)
    copies: list = field(default_factory=list)  # the frame numbers of the request's copies (it arrived again)
    undelivered: str | None = None  # why its addressee never got it (a relay did not deliver it): nothing answers it
    expired: bool = False  # its bound passed unanswered: a reply echoing it is late (judged then), not another's
    restarts: int = 0  # copies whose replies began a sequence of states afresh


class PassiveExchanges:
    """A tracker of one capture's exchanges. ``anyone``: the system id meaning "no system in particular";
    ``nobody``: a destination no system answers for (a request to it is addressed elsewhere); ``bounds``: the suite's
    timing bounds, which exchanges name; ``silence``: the rules under which any request may go unanswered."""

    def __init__(self, wire, exchanges: list[dict], edition: str, scale: float = 1.0, anyone: int | None = None,
                 bounds: dict | None = None, nobody: int | None = None, silence=(), ambiguities: dict | None = None):
        self.wire, self.anyone, self.edition, self.bounds = wire, anyone, edition, bounds or {}
        self.ambiguities = ambiguities or {}  # id -> the register's entry: a SHOULD entry's silence is NON_STRICT
        self.nobody, self.silence = nobody, tuple(silence)
        self.state_cache: dict[tuple, States] = {}
        self.rules = [self._resolve(ex, edition, scale) for ex in exchanges]
        self.by_request: dict[str, list[_Rule]] = {}
        self.by_reply: dict[str, list[_Rule]] = {}
        for rule in self.rules:
            self.by_request.setdefault(rule.exchange["request"]["message"], []).append(rule)
            self.by_reply.setdefault(rule.exchange["reply"], []).append(rule)
        self.open: dict[int, deque[_Open]] = {id(r): deque() for r in self.rules}  # in deadline order
        self.ended: dict[int, deque[_Open]] = {id(r): deque() for r in self.rules}  # answered, kept one more bound
        self.keyed: dict[tuple, list[_Open]] = {}
        self.pairs: set[tuple] = set()  # (rule, requester, node) of every request seen
        self.senders: dict = {}  # system id -> the address and port its frames come from
        self.next_deadline = float("inf")
        self.losses: list[list] = []  # [from, to, why, requesters or None]: times the frames do not tell all of
        self.undoing = {m: [r["after"] for r in (*self.silence, *(x for rule in rules for x in
                                                                   rule.exchange.get("silence", ()))) if "after" in r]
                        for m, rules in self.by_request.items()}  # request message -> what its silence rules' after select
        self.undone: deque = deque(maxlen=UNDONE_KEPT)  # (frame number, src, dst, fields) of the messages they selected

    @property
    def messages(self) -> set[str]:
        """The messages whose fields the tracker needs."""
        return set(self.by_request) | set(self.by_reply)

    def observe(self, w: Watched) -> list[Finding]:
        out = self._expire(w.time) if w.time > self.next_deadline else []
        origin = (getattr(w.where, "src", None), getattr(w.where, "sport", None))  # the datagram's sender
        if w.src != w.dst and origin[0] is not None and self.senders.get(w.dst) == origin:
            return out  # sent from its addressee's own address: echoed back by it (DUNE's router does), not new
        if w.src != w.dst:  # a frame to its own source (a forgery of the node's id sent to it) says not where it is
            self.senders[w.src] = origin
        answers = False  # a frame that answers an open request is not a new request (CLEAR answers CLEAR)
        for rule in self.by_reply.get(w.message, ()):
            if _matches(w.fields, rule.reply_when):
                found = self._reply(rule, w)
                answers = answers or found is not None
                out += found or []
        for rule in () if answers else self.by_request.get(w.message, ()):
            if _matches(w.fields, rule.when) and not self._replying(w):
                out += self._request(rule, w)
                break
        if any(selected(self.wire, w.message, w.fields, after, self.edition) for after in self.undoing.get(w.message, ())):
            self.undone.append((w.number, w.src, w.dst, w.fields))
        return out

    def _replying(self, w: Watched) -> bool:
        """Whether ``w`` goes back the way a request of its kind came (a late reply, when request and reply are
        the same message), so it is no new request."""
        return any(_matches(w.fields, rule.reply_when) and (id(rule), w.dst, w.src) in self.pairs
                   for rule in self.by_reply.get(w.message, ()))

    def due(self, now: float) -> list[Finding]:
        """Judge every exchange whose bound has passed by ``now``: a clock that runs on frames no exchange watches
        (a log's other traffic) decides what is due before anything later can split it."""
        return self._expire(now) if now > self.next_deadline else []

    def lost(self, start: float, end: float, why: str = "datagrams were lost meanwhile", requesters=None) -> list:
        """Between ``start`` and ``end`` the frames do not tell all (``why``: a watcher's receive buffer overflowed,
        a log's clock jumped, a relay dropped or held a datagram): an absence across that time (a request left
        unanswered, a sequence left unended) is not judged; an answer that came is (``requesters``: only the requests
        of these systems; None: every request). A time overlapping the last one given for the same requesters, or
        within LOSS_GAP of it, extends it, so that a flood of losses takes no more room than one. The time's entry, whose end (index 1) a
        caller may move once it knows it (``end`` infinite until then)."""
        if self.losses and end != float("inf"):
            last = self.losses[-1]
            if last[3] == requesters and last[1] != float("inf") and start <= last[1] + LOSS_GAP and end >= last[0]:
                last[0], last[1] = min(last[0], start), max(last[1], end)
                return last
        self.losses.append([start, end, why, requesters])
        return self.losses[-1]

    def withdraw(self, number: int, why: str) -> None:
        """The request seen as frame ``number`` never reached its addressee (``why``: a relay did not deliver it): no
        reply answers it (a reply to a later request like it is that request's), and its absence is not judged."""
        for queue in self.open.values():
            for o in queue:
                if o.request.number == number:
                    o.undelivered = why
                    return

    def again(self, w: Watched) -> None:
        """``w`` is a copy of a request seen before (the network, or a relay, delivered it twice): its addressee may
        answer each copy, so a second sequence of replies is no status after the terminal one, and what the seeds
        leave open about the request is not read (INCONCLUSIVE)."""
        for rule in self.by_request.get(w.message, ()):
            if not _matches(w.fields, rule.when):
                continue
            key = tuple(hashable(w.fields.get(e["request_field"])) for e in rule.echoes)
            for o in reversed(self.keyed.get((id(rule), key), ())):
                if o.request.src == w.src and o.request.dst == w.dst and same(o.request.fields, w.fields):
                    o.copies.append(w.number)
                    return

    def split(self, why: str) -> tuple[list[Finding], int]:
        """The frames' clock jumped (``why``): no bound can be timed across the jump, so every exchange still open is
        closed INCONCLUSIVE (never PASS, never FAIL), and the next frames begin afresh (a reply to a request before
        the jump answers nothing). The findings, and how many exchanges were open."""
        out, count = [], 0
        for queue in self.open.values():
            for o in queue:
                found = self._unjudged(o, why)
                count += bool(found)
                out += found
        for table in (self.open, self.ended):
            for queue in table.values():
                queue.clear()
        self.keyed.clear()
        self.next_deadline = float("inf")
        return out, count

    def _unjudged(self, o: _Open, why: str) -> list[Finding]:
        """The findings on an exchange left open (``why``): INCONCLUSIVE, never PASS, never FAIL."""
        if not o.answered:
            return [self._finding(o, "answered", Verdict.INCONCLUSIVE, o.rule.exchange["clause"],
                                  f"no {o.rule.exchange['reply']} {self._between(o)} before {why}", o.request)]
        found = [f for f in self._expired(o) if f.verdict is not Verdict.PASS]
        for f in found:
            f.verdict, f.detail = Verdict.INCONCLUSIVE, f"{f.detail}; not judged: {why}"
        return found

    def finish(self, end: float) -> list[Finding]:
        """Judge what the end of the capture decides; a request whose bound reaches past it is INCONCLUSIVE."""
        out = self._expire(end)
        for o in (o for queue in self.open.values() for o in queue):
            if not o.answered and o.orphans:  # a reply came, echoing another value: that is decided
                out += self._judge_expired(o)
            elif not o.answered:
                out.append(self._finding(o, "answered", Verdict.INCONCLUSIVE, o.rule.exchange["clause"],
                                         f"the capture ends {end - o.request.time:.3f} s after the request, before "
                                         f"its bound of {_bound(o)}", o.request))
        return out

    # ------------------------------------------------------------ requests

    def _request(self, rule: _Rule, w: Watched) -> list[Finding]:
        """Follow a request; the findings on one left unjudged to make room for it (OPEN_LIMIT)."""
        key = tuple(hashable(w.fields.get(e["request_field"])) for e in rule.echoes)
        same_key = self.keyed.setdefault((id(rule), key), [])
        if any(not o.answered and o.undelivered is None and o.request.src == w.src and o.request.dst == w.dst
               and same(o.request.fields, w.fields) for o in same_key):
            return []  # a resend of an open request is the same exchange
        out, queue = [], self.open[id(rule)]
        if len(queue) >= OPEN_LIMIT:
            gone = queue.popleft()
            if not gone.answered:
                self.keyed[(id(rule), gone.key)].remove(gone)
            out = self._unjudged(gone, f"{OPEN_LIMIT:,} later requests of its exchange were open at once (not "
                                       "followed further)")
        # a relay's requester could not see the time the relay added to the request's trip and its reply's
        deadline = _latest(w) + rule.within + getattr(w.where, "added", 0.0)
        o = _Open(rule, w, key, deadline, states=self._states(rule, w.fields) if rule.stateful else None)
        self.pairs.add((id(rule), w.src, w.dst))
        same_key.append(o)
        if queue and queue[-1].deadline > o.deadline:  # a request timed by a bracket may end before an earlier one
            queue.insert(bisect.bisect_right(queue, o.deadline, key=_deadline), o)
        else:
            queue.append(o)
        self.next_deadline = min(self.next_deadline, o.deadline)
        return out

    # ------------------------------------------------------------ replies

    def _reply(self, rule: _Rule, w: Watched) -> list[Finding] | None:
        """The findings on a reply to an open request; None if it answers none."""
        if rule.echoes:
            key = tuple(hashable(w.fields.get(e["reply_field"])) for e in rule.echoes)
            mine = self.keyed.get((id(rule), key), ())
        else:  # replies correlate by addressing alone
            mine = (o for o in self.open[id(rule)] if o.request.src == w.dst or w.dst == self.anyone)
        o = self._answered_by(mine, w)
        if o is None:
            if rule.echoes and any(p.expired and p.request.src == w.dst and self._from_node(p, w) for p in mine):
                return []  # a late reply to a request judged when its bound passed
            if rule.echoes:
                for other in self.open[id(rule)]:
                    if not other.answered and other.undelivered is None and other.request.src == w.dst \
                            and self._from_node(other, w):
                        other.orphans.append(w)
            return None
        ex, out = rule.exchange, []
        for c in ex["correlation"]:
            if c["kind"] == "to-requester":
                ok = w.dst == o.request.src
                out.append(self._finding(o, "to-requester", Verdict.PASS if ok else LEVELS[c["level"]], c["clause"],
                                         "" if ok else f"{w.message} sent to system {show(w.dst)}, not to the "
                                                       f"requester {show(o.request.src)}", w))
        if not o.answered:  # not past the bound: a request is judged unanswered once its bound has surely passed
            o.answered = True
            late = self._late(o, w)
            o.unsure = bool(late)
            out.append(self._finding(o, "answered", Verdict.INCONCLUSIVE if late else Verdict.PASS, ex["clause"],
                                     late and f"{ex['reply']} {late}", w))
        if o.states is not None:
            out += self._state(o, w)
        return out

    def _state(self, o: _Open, w: Watched) -> list[Finding]:
        states = o.states
        value = w.fields.get(states.field)
        out = []
        if o.terminal is not None and len(o.copies) > o.restarts:  # the copy's own replies begin
            o.restarts += 1
            o.terminal = o.open_end = None
        if o.terminal is not None:
            if o.open_end is None:
                return [self._finding(o, "after-terminal", LEVELS[states.level], states.clause,
                                      f"{self._said(w, states.field)} after the terminal state "
                                      f"(frame {o.terminal.number})", w)]
            out.append(self._finding(o, f"reading/{o.open_end}", Verdict.IMPL_DEFINED, states.clause,
                                     f"the open state of frame {o.terminal.number} was followed by "
                                     f"{self._said(w, states.field)}: read as a delay (open reading {o.open_end})", w))
            o.terminal = o.open_end = None
        kind = states.kind(value)
        if kind == "terminal" or kind == "open" or (kind == "unknown" and states.unknown is not None):
            o.terminal, o.open_end = w, (None if kind == "terminal" else states.open.get(hashable(value), states.unknown))
            late = self._late(o, w)
            out.append(self._finding(o, "terminal", Verdict.INCONCLUSIVE if late else Verdict.PASS, states.clause,
                                     late and f"terminal {self._said(w, states.field)} {late}", w))
        return out

    def _states(self, rule: _Rule, fields: dict) -> States:
        """The states of a request's replies, resolved once per exchange and request value (a bounded cache: a
        capture may hold any value)."""
        by = rule.exchange["state"].get("by_request")
        key = (id(rule), hashable(fields.get(by["field"])) if by else None)
        states = self.state_cache.get(key)
        if states is None:
            states = states_for(self.wire, rule.exchange, fields, self.edition)
            if len(self.state_cache) < STATE_CACHE:
                self.state_cache[key] = states
        return states

    def _answered_by(self, mine, w: Watched) -> _Open | None:
        """The request a reply answers among those it matches: its addressee's before another system's, and the
        oldest not yet answered before the latest answered (whose statuses go on)."""
        open_other = latest_mine = latest_other = None
        anyone, sender = self.anyone, w.src
        for o in mine:  # oldest first
            if o.undelivered is not None or o.expired:
                continue
            node = o.request.dst
            if (sender == o.request.src) if node in (None, anyone, self.nobody) else (sender != node):
                continue  # not from the system the request was for (see _from_node)
            if o.request.src == w.dst:
                if not o.answered:
                    return o
                latest_mine = o
            else:
                open_other = open_other or (None if o.answered else o)
                latest_other = o
        return latest_mine or open_other or latest_other

    def _from_node(self, o: _Open, w: Watched) -> bool:
        """Whether ``w`` comes from the system the request was for (any other than the requester, for a request
        to no system in particular)."""
        if o.request.dst in (None, self.anyone, self.nobody):
            return w.src != o.request.src
        return w.src == o.request.dst

    # ------------------------------------------------------------ bounds

    def _expire(self, now: float) -> list[Finding]:
        out = []
        for rid, queue in self.open.items():
            while queue and queue[0].deadline < now:
                o = queue.popleft()
                out += self._judge_expired(o)
            ended = self.ended[rid]
            while ended and now - ended[0].deadline > ended[0].rule.within:
                gone = ended.popleft()
                self.keyed[(rid, gone.key)].remove(gone)
        self.next_deadline = min((q[0].deadline for q in self.open.values() if q), default=float("inf"))
        return out

    def _judge_expired(self, o: _Open) -> list[Finding]:
        """A request's findings once its bound has passed. Only an absence (no reply, no terminal state) is excused
        by what the frames do not tell; a reply that came echoing another value is judged whatever was lost around
        it. What the seeds leave open about an answered request that arrived twice is not read: the second answer may
        be the copy's."""
        findings = self._expired(o)
        absent = (not o.answered and not (o.orphans and o.rule.echoes)) or (o.states is not None and o.terminal is None)
        if o.unsure:
            why = "its first reply may have come after the bound (the log's clocks tell no closer)"
        elif absent:
            why = o.undelivered or next((why for start, end, why, systems in self.losses if start <= o.deadline and
                                         end >= o.request.time and (systems is None or o.request.src in systems)), None)
        else:
            why = None
        if why is None and o.copies and o.answered:  # a copy adds answers; it never takes one away
            why = f"the request arrived {len(o.copies) + 1} times (frames {o.request.number}, " \
                  f"{', '.join(map(str, o.copies))}): its addressee may have answered each copy"
            excused = (Verdict.NON_STRICT, Verdict.IMPL_DEFINED)
        else:
            excused = (Verdict.FAIL, Verdict.NON_STRICT, Verdict.IMPL_DEFINED)
        if why is not None:
            for f in findings:  # the reply, or the right one, may have been lost; a reading rests on no absence seen
                if f.verdict in excused:
                    f.verdict, f.detail = Verdict.INCONCLUSIVE, f"{f.detail}; not judged: {why}"
        return findings

    def _expired(self, o: _Open) -> list[Finding]:
        ex, bound = o.rule.exchange, _bound(o)
        if not o.answered:
            o.expired = True  # kept one more bound, so that a late reply is known for its own
            self.ended[id(o.rule)].append(o)
            if o.orphans and o.rule.echoes:
                w = o.orphans[0]
                e = next((e for e in o.rule.echoes if not same(w.fields.get(e["reply_field"]),
                                                                o.request.fields.get(e["request_field"]))),
                         o.rule.echoes[0])
                asked = self._name(o.request.message, e["request_field"], o.request.fields.get(e["request_field"]))
                echoed = self._name(w.message, e["reply_field"], w.fields.get(e["reply_field"]))
                return [self._finding(o, f"echo-{e['request_field']}", LEVELS[e["level"]], e["clause"],
                                      f"no {ex['reply']} echoed {e['request_field']}={asked} within {bound}; "
                                      f"this one carries {e['reply_field']}={echoed}", w)]
            silent = silence_allowed(self.wire, ex, o.request.fields, self.edition, self._facts(o), self.silence)
            if silent is not None:  # the seeds require no reply to this request: a reading, never a failure
                return [self._reading(o, silent, f"no {ex['reply']} {self._between(o)} within {bound}")]
            return [self._finding(o, "answered", LEVELS[ex["level"]], ex["clause"],
                                  f"no {ex['reply']} {self._between(o)} within {bound}", o.request)]
        self.ended[id(o.rule)].append(o)
        if o.states is not None and o.terminal is None:
            what = f"no terminal {ex['reply']} within {bound}"
            unended = silence_allowed(self.wire, ex, o.request.fields, self.edition, self._facts(o), self.silence,
                                      unended=True)
            if unended is not None:  # a later request reusing its identifier may have replaced it
                return [self._reading(o, unended, what)]
            return [self._finding(o, "terminal", LEVELS[weaker(ex["level"], o.states.level)], o.states.clause, what,
                                  o.request)]
        if o.open_end is not None:  # it ended in a state the seeds leave open: the reading, shown
            named = self._name(o.terminal.message, o.states.field, o.terminal.fields.get(o.states.field))
            return [self._finding(o, f"reading/{o.open_end}", Verdict.IMPL_DEFINED, o.states.clause,
                                  f"ended in {o.states.field}={named}: read as the end of the request "
                                  f"(open reading {o.open_end})", o.terminal)]
        return []

    def _facts(self, o: _Open) -> dict:
        """What the silence rules may select an unanswered request by, as a capture shows it: where it was addressed,
        and (for exchanges whose rules ask) its echoed fields whose value an earlier request of the same requester to
        the same node carries (``reuses``) or a later one that was answered (``reused``: it may have replaced it); and the
        earlier messages of its kind from the same requester to the same node that a silence rule's ``after`` selects."""
        mine = o.request
        facts = {"to": "elsewhere" if mine.dst == self.nobody else None,
                 "earlier": [f for n, src, dst, f in self.undone if n < mine.number and src == mine.src and dst == mine.dst]}
        ex = o.rule.exchange
        if not any("reuses" in r or "reused" in r for r in ex.get("silence", ())):
            return facts
        rid = id(o.rule)
        others = [p for p in (*self.open[rid], *self.ended[rid]) if p is not o and not p.expired
                  and p.request.src == mine.src and p.request.dst == mine.dst]
        for fact, chosen in (("reuses", [p for p in others if p.request.number < mine.number]),
                             ("reused", [p for p in others if p.request.number > mine.number and p.answered])):
            facts[fact] = {e["request_field"] for e in o.rule.echoes if any(
                same(p.request.fields.get(e["request_field"]), mine.fields.get(e["request_field"])) for p in chosen)}
        return facts

    def _reading(self, o: _Open, ambiguity: str, what: str) -> Finding:
        """A request's silence the register reads: IMPL_DEFINED (an open reading), or NON_STRICT where the entry is a
        SHOULD (the seeds define a reply for the case without requiring it)."""
        should = self.ambiguities.get(ambiguity, {}).get("level") == "SHOULD"
        return self._finding(o, f"reading/{ambiguity}", Verdict.NON_STRICT if should else Verdict.IMPL_DEFINED,
                             o.rule.exchange["clause"],
                             f"{what} ({'register entry' if should else 'open reading'} {ambiguity})", o.request)

    def _late(self, o: _Open, w: Watched) -> str:
        """Why ``w``, which came before the request's bound surely passed, may yet have come after it (its time and
        the request's known only within brackets: frames of a log stamped by other clocks); "" if surely within."""
        allowed = o.deadline - _latest(o.request)  # the bound, and the time a relay added to the way
        if _latest(w) - o.request.time <= allowed:
            return ""
        early, late = max(0.0, w.time - _latest(o.request)), _latest(w) - o.request.time
        at_most = f"to {late:.3f} s" if late < float("inf") else "s or more (the request came before the log's " \
            "clock began)"
        return (f"came {early:.3f} {at_most} after the request (bound {_bound(o)}): the log's clocks tell no closer, "
                "not judged")

    # ------------------------------------------------------------ shared

    def _finding(self, o: _Open, aspect: str, verdict: Verdict, clause: str, detail: str, w: Watched) -> Finding:
        if detail and w is not o.request:
            detail = f"request frame {o.request.number}: {detail}"
        return Finding(o.request.message, f"exchange/{o.rule.exchange['id']}/{aspect}", verdict, clause, detail,
                       w.number, w.time, None, w.where, asker=o.request.where)

    def _between(self, o: _Open) -> str:
        """Who owed whom the reply: ``from system 30 to 19696``."""
        node = "any system" if o.request.dst in (None, self.anyone) else f"system {o.request.dst}"
        return f"from {node} to {o.request.src}"

    def _said(self, w: Watched, path: str) -> str:
        """What a frame said in one field: ``AcousticStatus status=SENT`` (built only for a finding's detail)."""
        return f"{w.message} {path}={self._name(w.message, path, w.fields.get(path))}"

    def _name(self, message: str, path: str, value) -> str:
        named = self.wire.present(Parsed(None, message, {"fields": {path: value}})).get("fields", {}).get(path, value)
        return named if isinstance(named, str) else show(named)

    def _resolve(self, ex: dict, edition: str, scale: float) -> _Rule:
        def values(message: str, when: dict) -> dict[str, frozenset]:
            return {f: frozenset(hashable(v) for v in resolved(self.wire, message, f, names, edition))
                    for f, names in when.items()}

        return _Rule(ex, values(ex["request"]["message"], ex["request"].get("when", {})),
                     values(ex["reply"], ex.get("reply_when", {})),
                     [c for c in ex["correlation"] if c["kind"] == "echo"], "state" in ex,
                     seconds(ex["within"], self.bounds) * scale)


def _deadline(o: _Open) -> float:
    return o.deadline


def _latest(w: Watched) -> float:
    """The latest time ``w`` can have been seen at."""
    return w.time if w.latest is None else w.latest


def _bound(o: _Open) -> str:
    """A request's bound in words: ``5 s``, or ``5 s (and the 4 s a relay added to the way)``."""
    added = o.deadline - _latest(o.request) - o.rule.within
    return f"{o.rule.within:g} s" + (f" (and the {added:.3g} s a relay added to the way)" if added > 1e-9 else "")


def _matches(fields: dict, when: dict[str, frozenset]) -> bool:
    return all(hashable(fields.get(f)) in values for f, values in when.items())

