"""Scenarios whose target is a handler the adapter calls (a suite's services: ros_acomms' dynamic queue and
modem driver), run through any adapter session: each call, publish or setup of a scenario is one request of
the adapter's own session (library or subprocess), and the call's answer is the reply.

A call takes no time: the scenario runs on virtual time, so a bound expires only when no reply can come (the
call was refused), and a run gives the same result to the byte whatever the machine's speed. Requests that are
not scenarios pass straight through to the adapter's session.
"""

from __future__ import annotations

import itertools
from typing import Iterable, Iterator

from ..core.session import Answer, Job, Request
from ..kinds.scenario import Addressing

EPOCH = 1_700_000_000.0  # the virtual clock's start, seconds since 1970
FAILURES = ("crash", "timeout", "adapter-error", "unsupported")


class CallTarget:
    """A session that runs call scenarios over an adapter's session (``inner``), and everything else through it."""

    def __init__(self, inner):
        self.inner = inner
        self.name = inner.name
        self._numbers = itertools.count(1)

    def hello(self) -> dict:
        return self.inner.hello()

    @property
    def stderr(self) -> str:
        return self.inner.stderr

    @property
    def incidents(self):
        return self.inner.incidents

    def close(self) -> None:
        self.inner.close()

    def run(self, jobs: Iterable[Job]) -> Iterator[tuple[Job, Answer]]:
        jobs = list(jobs)
        yield from self.inner.run([j for j in jobs if j.request.op != "scenario"])
        for job in (j for j in jobs if j.request.op == "scenario"):
            yield job, self._scenario(job)

    def _scenario(self, job: Job) -> Answer:
        program = job.request.params["program"]
        if getattr(program.wire, "transport", None) != "call":
            return Answer("adapter-error", reason="this scenario needs a live target (--target), not an adapter")
        machine = program.machine(Addressing(), lambda _name: next(self._numbers), [program])
        t = 0.0
        pending = machine.start(t, EPOCH + t)
        for n in itertools.count(1):
            if pending:
                composed = pending.pop(0)
                answer = self._perform(job, n, composed)
                if answer.kind in FAILURES:
                    step = composed.extra.get("step", "?")
                    return Answer(answer.kind, reason=f"step {step}: {answer.reason}", note=answer.note)
                try:
                    pending += self._delivered(machine, t, composed, answer)
                except ValueError as exc:  # an answer not in the decoded form: the adapter's fault
                    return Answer("adapter-error", reason=f"step {composed.extra.get('step', '?')}: {exc}")
                continue
            if machine.done or machine.deadline is None:
                break
            t = machine.deadline
            pending += machine.wake(t, EPOCH + t)
        return Answer("ok", message=machine.record(0))

    def _perform(self, job: Job, n: int, composed) -> Answer:
        """One call of the scenario as a request of the adapter's session."""
        body = dict(composed.data)
        op = body.pop("op")
        call = Job(job.suite, job.case_id, Request(f"{op}-{n}", op, params=body))
        answered = [answer for _, answer in self.inner.run([call])]
        return answered[0] if answered else Answer("adapter-error", reason="the adapter session gave no answer")

    @staticmethod
    def _delivered(machine, t: float, composed, answer: Answer) -> list:
        """Tell the machine what the call got: an acknowledgement (or refusal), and for a call, the response."""
        step = composed.extra.get("step", "")
        if answer.kind == "rejected":
            return machine.acknowledge(t, EPOCH + t, step, answer.reason or "refused")
        out = machine.acknowledge(t, EPOCH + t, step, None)
        parsed = machine.wire.reply(composed, answer.message)
        if parsed is not None:
            out += machine.deliver(t, EPOCH + t, parsed, adopt=True)
        return out
