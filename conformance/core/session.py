"""How the runner talks to an implementation, whatever the adapter kind: requests, answers, sessions.

A case kind plans ``Request``s for a case; a session performs them (``run(jobs)`` yields ``(job, Answer)``
for every job, in any order, so that a subprocess adapter can pipeline and a live endpoint can answer
asynchronously) and the kind judges each answer. Library, subprocess and socket adapters are sessions.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Iterable, Iterator, Protocol


@dataclass(slots=True)
class Request:
    """One operation asked of the implementation for one check of a case.

    ``op``: ``encode`` (``message`` in ``encoding``), ``decode`` (``frame``), ``roundtrip`` (decode
    ``frame``, then encode the implementation's own answer in ``encoding``) or ``describe`` (a type's
    definition). ``params``: the suite's further parameters of the operation as the adapter protocol names
    them (e.g. the name of the type to decode, where a frame does not say it).
    """

    check: str
    op: str
    encoding: str | None = None
    message: dict | None = None
    frame: bytes | None = None
    params: dict = field(default_factory=dict)
    context: object = None  # what the case kind that planned it keeps for judging the answer (sessions ignore it)


@dataclass(slots=True)
class Answer:
    """What the implementation did: ``ok`` with a frame, a message or a description, or a refusal, or a
    failure to answer."""

    kind: str  # "ok" | "rejected" | "unsupported" | "crash" | "timeout" | "adapter-error"
    frame: bytes | None = None
    message: dict | None = None
    reason: str = ""
    rule: str | None = None
    note: str = ""  # how the answer was obtained, when that matters (e.g. replayed after a protocol violation)


@dataclass(slots=True)
class Job:
    """One request of one case (its check names it within the case)."""

    suite: str
    case_id: str
    request: Request


class Session(Protocol):
    name: str

    def hello(self) -> dict: ...

    def run(self, jobs: Iterable[Job]) -> Iterator[tuple[Job, Answer]]: ...

    @property
    def stderr(self) -> str: ...

    @property
    def incidents(self) -> list: ...

    # A session may also have ``notes``: what the report should say about how it went (read after the run).

    def close(self) -> None: ...


class AdapterStartError(Exception):
    """The adapter could not be loaded, started or greeted: a usage/adapter error (exit code 2)."""
