"""Run many scenario machines against one target at once, sans-IO.

Scenarios that share a resource (declared, or a message they wait for) run one after another; the others
run together, so a set costs about its longest chain, not its sum. What arrives is parsed once and
routed: a reply that echoes a value a scenario's request carried (a request id, a sequence number), or that
is addressed to the entity a scenario's requests came from, goes to that scenario only, and a late reply to a
scenario that has ended goes to nobody; anything else goes to every running scenario, which takes what its current step waits for. The caller does the I/O: it sends
what ``start``/``deliver``/``wake`` return, calls ``wake`` at ``deadline``, and collects ``finished``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from .machine import Machine, Program, _hashable
from .wire import Addressing, Composed


@dataclass(frozen=True)
class Outgoing:
    job: object
    composed: Composed


class Conductor:
    def __init__(self, jobs: list, program_of: Callable, addressing: Addressing, epoch: Callable[[float], float],
                 first_unique: int = 1000, entities: range = range(1, 250)):
        """``jobs``: in the order to run them; ``program_of(job)``: its Program; ``epoch(t)``: seconds since
        1970 at monotonic time t (what the session stamps frames with)."""
        self.jobs = list(jobs)
        self.pending = list(range(len(self.jobs)))  # jobs by index (a job need not be hashable)
        self.program_of, self.addressing, self.epoch = program_of, addressing, epoch
        self.running: dict[int, Machine] = {}
        self.finished: list[tuple[object, Machine]] = []
        self.owners: dict[tuple, object] = {}
        self.entities: dict[int, int] = {}  # the entity each job's requests came from (the latest job wins)
        self._next_unique, self._entities, self._entity = first_unique, entities, 0

    @property
    def done(self) -> bool:
        return not self.pending and not self.running

    @property
    def deadline(self) -> float | None:
        times = [m.deadline for m in self.running.values() if m.deadline is not None]
        return min(times, default=None)

    def unique(self, _name: str) -> int:
        """A number no other request of the run carries (request ids, sequence numbers)."""
        self._next_unique = self._next_unique % 0xFFF0 + 1
        return self._next_unique

    def start(self, t: float) -> list[Outgoing]:
        out = []
        busy = set().union(*(m.program.resources() for m in self.running.values()))
        for job in list(self.pending):
            program: Program = self.program_of(self.jobs[job])
            if program.resources() & busy:
                continue
            self.pending.remove(job)
            busy |= program.resources()
            entity = self._entities[self._entity % len(self._entities)]
            self._entity += 1
            addressing = Addressing(self.addressing.system, entity, self.addressing.node)
            self.entities[entity] = job
            machine = Machine(program, addressing, self.unique)
            self.running[job] = machine
            out += self._sent(job, machine, machine.start(t, self.epoch(t)))
        return out + self._reap(t)

    def deliver(self, t: float, parsed) -> list[Outgoing]:
        out = []
        owner = self._owner(parsed)
        if owner is not None:
            targets = [owner] if owner in self.running else []
        else:
            targets = list(self.running)
        watchers = [j for j in targets if self.running[j].watches(parsed)]
        for i, job in enumerate(targets):
            machine = self.running[job]
            adopt = parsed.problem is not None and not watchers and i == 0
            if parsed.problem is not None and watchers and job not in watchers:
                continue
            out += self._sent(job, machine, machine.deliver(t, self.epoch(t), parsed, adopt))
        return out + self._reap(t)

    def wake(self, t: float) -> list[Outgoing]:
        out = []
        for job, machine in list(self.running.items()):
            if machine.deadline is not None and machine.deadline <= t:
                out += self._sent(job, machine, machine.wake(t, self.epoch(t)))
        return out + self._reap(t)

    def abandon(self) -> list[tuple[object, Machine]]:
        """Every job not finished (the run was stopped): those running, then those pending."""
        return [(self.jobs[j], self.running[j]) for j in self.running] + [(self.jobs[j], None) for j in self.pending]

    def _owner(self, parsed):
        """The job a reply belongs to: the one whose request it echoes (the latest to send such a request), else
        the one it is addressed to (the session gives each scenario its own entity), if any."""
        if parsed.decoded is None:
            return None
        owner = None
        for (message, echoes), job in self.owners.items():
            if message == parsed.message and all(_hashable(parsed.fields.get(f)) == v for f, v in echoes):
                owner = job
        if owner is None and self.jobs:
            to = self.program_of(self.jobs[0]).wire.destination(parsed)
            if to is not None and to[0] == self.addressing.system and to[1] in self.entities:
                owner = self.entities[to[1]]
        return owner

    def _sent(self, job, machine: Machine, composed: list[Composed]) -> list[Outgoing]:
        while len(machine.keys) > machine.keys_seen:
            key = machine.keys[machine.keys_seen]
            machine.keys_seen += 1
            self.owners.pop(key, None)
            self.owners[key] = job  # a later request with the same echoed values takes the replies over
        return [Outgoing(job, c) for c in composed]

    def _reap(self, t: float) -> list[Outgoing]:
        ended = [job for job, m in self.running.items() if m.done]
        for job in ended:
            self.finished.append((self.jobs[job], self.running.pop(job)))
        return self.start(t) if ended and self.pending else []
