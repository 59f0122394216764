"""Run many scenario machines against one target at once, sans-IO.

Scenarios that share a resource (declared, or a message they wait for) run one after another; the others
run together, so a set costs about its longest chain, not its sum. While the target is gone (``absent``: the
session's liveness), what each scenario waits for is decided at once rather than at each bound. A program may be ``exclusive`` (it runs
alone: the robustness phase floods the target) and may belong to a ``batch`` (programs of one batch share
one machine: the robustness phase probes every request kind after each block of frames it sends). What
arrives is parsed once and routed: a reply that echoes a value a scenario's request carried (a request id,
a sequence number), or that is addressed to the entity a scenario's requests came from, goes to that
scenario only, and a late reply to a scenario that has ended goes to nobody; anything else goes to every
running scenario, which takes what its current step waits for.

A reply addressed to the session's own id whose echoed number is far from every number the run's requests
carried answers a request the run never sent: another system is using the session's id (``impostors`` says
so; a node that does not echo is off by little, and fails the echo rule instead).

The caller does the I/O: it sends what ``start``/``deliver``/``wake``/``restarted`` return, calls ``wake`` at
``deadline``, restarts the target when ``restart_wanted`` says so (then calls ``restarted``), and collects
``finished`` as (job, record).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from ...limits import UNIQUE_SPAN
from .matchers import hashable
from .wire import Addressing, Composed

NEAR = 256  # how far off a run's own number an echoed one may be and still be taken for a node's mistake


@dataclass(frozen=True)
class Outgoing:
    job: object
    composed: Composed


class Conductor:
    def __init__(self, jobs: list, program_of: Callable, addressing: Addressing, epoch: Callable[[float], float],
                 first_unique: int = 1000, entities: range = range(1, 250)):
        """``jobs``: in the order to run them; ``program_of(job)``: its program; ``epoch(t)``: seconds since
        1970 at monotonic time t (what the session stamps frames with)."""
        self.jobs = list(jobs)
        self.pending = list(range(len(self.jobs)))  # jobs by index (a job need not be hashable)
        self.program_of, self.addressing, self.epoch = program_of, addressing, epoch
        self.running: dict[int, object] = {}  # first member's index -> machine
        self.members: dict[int, list[int]] = {}  # first member's index -> every job the machine runs
        self.finished: list[tuple[object, dict]] = []
        self.owners: dict[tuple, int] = {}
        self.entities: dict[int, int] = {}  # the entity each machine's requests came from (the latest wins)
        self._first_unique = self._next_unique = first_unique % UNIQUE_SPAN
        self._entities = entities
        self._released: set[int] = set()  # machines seen to have released their resources
        self.impostors: list[str] = []  # replies that answer requests this run never sent
        self.lasting: list[str] = []  # impairments every machine started from now on is told of
        self.gone: str | None = None  # why the target is taken for gone (liveness), or None

    @property
    def done(self) -> bool:
        return not self.pending and not self.running

    @property
    def deadline(self) -> float | None:
        times = [m.deadline for m in self.running.values() if m.deadline is not None]
        return min(times, default=None)

    @property
    def restart_wanted(self) -> bool:
        return any(getattr(m, "restart_wanted", False) for m in self.running.values())

    def unique(self, _name: str) -> int:
        """A number no other request of the run carries (request ids, sequence numbers)."""
        self._next_unique = self._next_unique % UNIQUE_SPAN + 1
        return self._next_unique

    def start(self, t: float) -> list[Outgoing]:
        out = []
        programs = {j: self.program_of(self.jobs[j]) for j in self.pending}
        if any(getattr(self.program_of(self.jobs[k]), "exclusive", False) for k in self.running):
            return []
        busy = set().union(*(self.program_of(self.jobs[k]).resources() for k, m in self.running.items()
                             if not getattr(m, "released", False)))
        for job in list(self.pending):
            if job not in self.pending:
                continue  # started with its batch
            program = programs[job]
            if getattr(program, "exclusive", False):
                if self.running:
                    break  # it waits for what runs, and nothing after it starts before it
            elif program.resources() & busy:
                continue
            batch = getattr(program, "batch", None)
            members = [j for j in self.pending if batch is not None and getattr(programs[j], "batch", None) is batch] or [job]
            for j in members:
                self.pending.remove(j)
            busy |= program.resources()
            entity = self._entity_for(job)
            addressing = self.addressing.for_entity(entity)
            self.entities[entity] = job
            machine = program.machine(addressing, self.unique, [programs[j] for j in members])
            self.running[job], self.members[job] = machine, members
            for why in self.lasting:
                machine.impaired(t, why, lasting=True)
            out += self._sent(job, machine, machine.start(t, self.epoch(t)))
            if self.gone is not None and hasattr(machine, "gone"):
                out += self._sent(job, machine, machine.gone(t, self.epoch(t), self.gone))
            if getattr(program, "exclusive", False):
                break
        return out + self._reap(t)

    def _entity_for(self, job: int) -> int:
        """The entity a job's requests come from: by its place in the run, not by when it started (a replay that
        starts two jobs of one instant in the other order addresses them as the live run did), unless a running
        machine still speaks from it."""
        taken = {m.addressing.entity for m in self.running.values() if hasattr(m, "addressing")}
        for i in range(len(self._entities)):
            entity = self._entities[(job + i) % len(self._entities)]
            if entity not in taken:
                return entity
        return self._entities[job % len(self._entities)]

    def deliver(self, t: float, parsed) -> list[Outgoing]:
        out = []
        owner = self._owner(parsed)
        if owner is None:
            foreign = self._foreign(parsed)
            if foreign is not None and foreign not in self.impostors:
                self.impostors.append(foreign)
                self.impaired(t, foreign, lasting=True)
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

    def restarted(self, t: float, problem: str | None) -> list[Outgoing]:
        """The target was restarted (``problem``: why it could not be, or None)."""
        out = []
        for job, machine in list(self.running.items()):
            if getattr(machine, "restart_wanted", False):
                out += self._sent(job, machine, machine.restarted(t, self.epoch(t), problem))
        return out + self._reap(t)

    def impaired(self, t: float, why: str, lasting: bool = False) -> None:
        """The link could not show everything (``why``): every running machine is told (a step failing for want of
        a frame is then INCONCLUSIVE); ``lasting``: for the rest of the run (another system using the session's id),
        so machines started later are told too."""
        if lasting and why not in self.lasting:
            self.lasting.append(why)
        for machine in self.running.values():
            machine.impaired(t, why, lasting)

    def absent(self, t: float, why: str | None) -> list[Outgoing]:
        """The target is gone (``why``: the session's liveness says so), or back (None): while it is gone, what every
        scenario waits for is decided at once (machines that can be told), not at the end of each bound."""
        self.gone = why
        out = []
        if why is not None:
            for job, machine in list(self.running.items()):
                if hasattr(machine, "gone"):
                    out += self._sent(job, machine, machine.gone(t, self.epoch(t), why))
        return out + self._reap(t)

    def undeliverable(self, t: float, job, why: str) -> list[Outgoing]:
        """What a job's machine sent could not be sent (``why``): it stops, unable to run (INCONCLUSIVE)."""
        for key, machine in self.running.items():
            if any(self.jobs[m] is job for m in self.members[key]):
                machine.cannot_run(t, why)
        return self._reap(t)

    def _owner(self, parsed) -> int | None:
        """The machine a reply belongs to: the one whose request it echoes (the latest to send such a request),
        else the one it is addressed to (the session gives each machine its own entity), if any."""
        if parsed.decoded is None:
            return None
        owner = None
        for (message, echoes), job in self.owners.items():
            if message == parsed.message and all(hashable(parsed.fields.get(f)) == v for f, v in echoes):
                owner = job
        if owner is None and self.jobs:
            to = self.program_of(self.jobs[0]).wire.destination(parsed)
            if to is not None and to[0] in (self.addressing.system, self.addressing.other) and to[1] in self.entities:
                owner = self.entities[to[1]]
        return owner

    def _foreign(self, parsed) -> str | None:
        """Why a reply addressed to the session's id answers a request the run never sent, or None."""
        if parsed.decoded is None or not self.jobs:
            return None
        to = self.program_of(self.jobs[0]).wire.destination(parsed)
        if to is None or to[0] != self.addressing.system:
            return None
        for message, echoes in self.owners:
            if message == parsed.message:
                values = [parsed.fields.get(name) for name, _ in echoes]
                if values and not any(self._near(v) for v in values):
                    shown = ", ".join(f"{name}={v}" for (name, _), v in zip(echoes, values))
                    return (f"a {message} to the session's id {self.addressing.system} answers a request this run never "
                            f"sent ({shown})")
                return None
        return None

    def _near(self, value) -> bool:
        """Whether a number is one the run's requests carried, or close to one (a node's mistake, not a stranger's)."""
        if not isinstance(value, int) or isinstance(value, bool) or not 0 < value <= UNIQUE_SPAN:
            return True  # not a number the run could have issued (text, a special value): no evidence either way
        issued = (self._next_unique - self._first_unique) % UNIQUE_SPAN
        offset = (value - self._first_unique) % UNIQUE_SPAN
        return offset <= issued + NEAR or offset >= UNIQUE_SPAN - NEAR

    def _sent(self, job: int, machine, composed: list[Composed]) -> list[Outgoing]:
        while len(machine.keys) > machine.keys_seen:
            key = machine.keys[machine.keys_seen]
            machine.keys_seen += 1
            self.owners.pop(key, None)
            self.owners[key] = job  # a later request with the same echoed values takes the replies over
        return [Outgoing(self.jobs[job], c) for c in composed]

    def _reap(self, t: float) -> list[Outgoing]:
        ended = [job for job, m in self.running.items() if m.done]
        for job in ended:
            machine = self.running.pop(job)
            for i, member in enumerate(self.members.pop(job)):
                self.finished.append((self.jobs[member], machine.record(i)))
        freed = {k for k, m in self.running.items() if getattr(m, "released", False)} - self._released
        self._released |= freed
        return self.start(t) if (ended or freed) and self.pending else []
