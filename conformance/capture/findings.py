"""What a suite's capture rules report about a datagram or an exchange, and the contract those rules meet."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

from ..core.verdicts import Verdict


@dataclass(slots=True)
class Frame:
    """What a suite makes of one datagram: the group its frame belongs to (None: a message the suite does not
    define, ``outside`` names it), the broken rule (None: valid) at ``offset``, and for the messages
    exchanges watch, its decoded fields and addressing."""

    group: str | None
    rule: str | None = None
    offset: int = 0
    detail: str = ""
    clause: str = ""
    outside: str = ""
    fields: dict | None = None
    src: int | None = None  # the sender's and the addressee's system ids, where the frame gives them
    dst: int | None = None
    undecided: bool = False  # ``rule`` says why the frame could not be judged (INCONCLUSIVE), not what it breaks
    undefined: bool = False  # (outside) no definition the suite has names its message at all


@dataclass(slots=True)
class Finding:
    """One judged thing, filed as case ``<suite>/<group>/capture/<case>``: a frame, an exchange's aspect, or what a
    log says of its frames (a connection's definition). ``number`` and ``time`` place it in the capture; ``frame``
    holds a failing frame's bytes."""

    group: str
    case: str
    verdict: Verdict
    clause: str
    detail: str = ""
    number: int | None = None
    time: float | None = None
    frame: bytes | None = None
    where: object = ""  # the datagram or logged frame it rests on (judge.py says where it is), or a text
    label: str | None = None  # what the report lists it as, where it is no frame (``connection 3``)
    asker: object = None  # an exchange's finding: the datagram of the request (its addressee answers for it)


@dataclass(slots=True)
class Watched:
    """A valid frame an exchange watches: where and when it was seen, its message, fields and addressing. ``time``
    is the earliest it can have been seen and ``latest`` the latest (None: ``time`` exactly; a frame of a log
    stamped by another system's clock is known only to lie between two of the logging system's frames)."""

    number: int
    time: float
    message: str
    fields: dict
    src: int | None
    dst: int | None
    where: object = ""  # the datagram that carried it
    latest: float | None = None


class CaptureRules(Protocol):
    """What a suite judges in captures: its usual ports, each datagram's frame, and the exchanges."""

    ports: frozenset[int]
    keys: dict[str, str]  # the groups frames are filed under, in report order, with the suite's key for each
    outside: str  # what is judged of a frame of a message the suite does not cover ("framing checked only")

    def frame(self, payload: bytes) -> Frame | None:
        """The frame in a datagram's payload, judged; None when the payload is not the suite's at all."""

    def exchanges(self, edition: str, scale: float) -> "ExchangeTracker":
        """A fresh tracker of the request/reply exchanges (time bounds multiplied by ``scale``)."""


class ExchangeTracker(Protocol):
    next_deadline: float  # the earliest bound of an exchange open

    def observe(self, frame: Watched) -> list[Finding]: ...

    def due(self, now: float) -> list[Finding]:
        """Judge every exchange whose bound has passed by ``now`` (a clock that runs without watched frames)."""

    def split(self, why: str) -> tuple[list[Finding], int]: ...

    def again(self, frame: Watched) -> None:
        """A copy of a frame observed before (delivered twice)."""

    def finish(self, end: float) -> list[Finding]: ...
