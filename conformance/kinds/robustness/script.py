"""What the robustness phase's script works with: the frames it replays, the state of each probe, and what it
yields to its driver (send a frame, wait for a reply or a time, restart the target)."""

from __future__ import annotations

from dataclasses import dataclass, field

from ..scenario.wire import Composed

FLOOD_ENTITY = 254  # the entity the replayed frames come from, so replies to them never look like a probe's


@dataclass(frozen=True)
class Frame:
    """A frame to replay: the corpus case it comes from, its encoding and what the case expects of it."""

    case_id: str
    encoding: str
    expect: str
    data: bytes
    addressed: bool = False  # sent as it is (a hostile block's), not readdressed to come from the session


@dataclass
class Probe:
    """One probe through the phase: whether it was answered before, and what silenced it since."""

    program: object  # the ProbeProgram it probes for
    baseline: bool = False
    down: bool = False  # silenced, and not served again since (no restart)
    silencings: list = field(default_factory=list)  # after what it stopped answering, and what bisecting found
    hostile: list = field(default_factory=list)  # the hostile blocks after which it stopped answering
    hostile_run: int = 0  # how many hostile blocks it was asked after
    blind: str | None = None  # why an unanswered round could not be judged (the link could not show everything)
    garbage: str | None = None  # what the garbage did to it
    error: str | None = None  # why its request cannot be sent


@dataclass(frozen=True)
class Send:
    """The script asks its driver to send a frame."""

    composed: Composed


@dataclass(frozen=True)
class Wait:
    """The script waits for a reply it accepts, or until a time."""

    until: float
    accepts: object = None  # Parsed -> bool, or None: only time ends the wait


class Restart:
    """The script asks the session to restart the target (it resumes with why it could not, or None)."""
