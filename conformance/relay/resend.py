"""What a requester does when the link loses its request, sans-IO: for each request of an idempotent exchange
(exchanges.json ``idempotent``) that the relay did not deliver intact, whether its requester sent it again within
the exchange's window (twice its bound). Every loss is read, once its window has ended inside the run; one whose
window the run's end cut short is INCONCLUSIVE. The suite names the ambiguity that records the answer (a requester's
resending is the suite's reading, not a rule): a resend is a PASS, none an IMPL_DEFINED reading, never a FAIL."""

from __future__ import annotations

from ..capture.datagrams import Datagram
from ..capture.findings import Finding
from ..core.verdicts import Verdict
from ..kinds.scenario.matchers import hashable

CASE = "request/resend-after-loss"
PENDING_LIMIT = 1024  # lost requests awaiting their resend at once; a loss beyond is not read (counted)


class ResendWatch:
    """``rules``: the exchanges tracker's rules (by request message); ``ambiguity``: (id, clause) of the reading."""

    def __init__(self, by_request: dict, ambiguity: tuple[str, str]):
        self.by_request, (self.ambiguity, self.clause) = by_request, ambiguity
        self.pending: dict[tuple, tuple[float, str, Datagram]] = {}  # key -> (deadline, group, the datagram lost)
        self.unread = 0  # losses not read (PENDING_LIMIT awaiting already)

    def _key(self, group: str, frame) -> tuple | None:
        if frame is None or frame.fields is None:
            return None
        for rule in self.by_request.get(group, ()):
            if rule.exchange.get("idempotent") and all(hashable(frame.fields.get(f)) in v for f, v in rule.when.items()):
                return (rule.exchange["id"], frame.src, frame.dst, hashable(frame.fields)), rule.within
        return None

    def undelivered(self, sent: Datagram, group: str, frame) -> None:
        """A datagram the link did not deliver intact (after ``sent`` saw it: a resend lost again awaits its own)."""
        found = self._key(group, frame)
        if found is None:
            return
        key, within = found
        if key not in self.pending and len(self.pending) >= PENDING_LIMIT:
            self.unread += 1
            return
        self.pending[key] = (sent.time + 2 * within, group, sent)

    def sent(self, sent: Datagram, group: str, frame) -> list[Finding]:
        """A datagram a side sent: a resend of a lost request?"""
        out = self.expire(sent.time)
        found = self._key(group, frame)
        if found is not None and found[0] in self.pending:
            _, group, lost = self.pending.pop(found[0])
            out.append(Finding(group, f"{CASE}/{found[0][0]}", Verdict.PASS, self.clause,
                               f"resent {sent.time - lost.time:.3f} s after the relay lost it (frame {lost.number})",
                               sent.number, sent.time, None, sent))
        return out

    def expire(self, t: float) -> list[Finding]:
        """The readings of the losses whose window ended by ``t``."""
        out = []
        for key in [k for k, (deadline, _, _) in self.pending.items() if deadline <= t]:
            deadline, group, lost = self.pending.pop(key)
            out.append(Finding(group, f"{CASE}/{key[0]}", Verdict.IMPL_DEFINED, self.clause,
                               f"the relay lost this request; its requester did not send it again within "
                               f"{deadline - lost.time:g} s (open reading {self.ambiguity})", lost.number, lost.time,
                               lost.payload, lost))
        return out

    def finish(self, t: float) -> list[Finding]:
        """At the end of the run (``t``): the windows that ended are read, the others are INCONCLUSIVE."""
        out = self.expire(t)
        for key, (deadline, group, lost) in self.pending.items():
            out.append(Finding(group, f"{CASE}/{key[0]}", Verdict.INCONCLUSIVE, self.clause,
                               f"the relay lost this request {t - lost.time:.3f} s before it stopped, within the "
                               f"{deadline - lost.time:g} s its requester has to send it again: not judged",
                               lost.number, lost.time, lost.payload, lost))
        self.pending.clear()
        return out
