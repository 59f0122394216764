"""How the runner talks to an implementation, whatever the adapter kind.

A session answers ``hello()`` and performs batches of jobs: ``run(jobs)`` yields ``(job, Answer)``
for every job, in any order, so that a subprocess adapter can pipeline requests and a live endpoint
can answer asynchronously. Library, subprocess and socket adapters are sessions.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable, Iterator, Protocol

from .evaluate import Answer, Request
from .results import Incident


@dataclass(slots=True)
class Job:
    """One request of one case: ``key`` is unique within a run (case id + check)."""

    key: str
    suite: str
    case: dict
    request: Request


class Session(Protocol):
    name: str

    def hello(self) -> dict: ...

    def run(self, jobs: Iterable[Job]) -> Iterator[tuple[Job, Answer]]: ...

    @property
    def stderr(self) -> str: ...

    @property
    def incidents(self) -> list[Incident]: ...

    def close(self) -> None: ...


class AdapterStartError(Exception):
    """The adapter could not be loaded, started or greeted: a usage/adapter error (exit code 2)."""
