"""What a scenario's state machine keeps: the findings it makes, the frames it looked at and the state of the
step it runs."""

from __future__ import annotations

from dataclasses import dataclass, field

from .wire import Parsed

STEP_KINDS = ("send", "setup", "expect", "sequence", "silence", "alive", "wait", "accepted")


@dataclass
class Finding:
    """One expectation of one step: ``check`` is ``step:<id>`` or ``step:<id>:<what>``."""

    check: str
    passed: bool
    level: str
    clause: str
    detail: str
    inconclusive: bool = False  # failed, but the session could not see everything it needed to judge


@dataclass
class Frame:
    """A frame the node sent that this scenario looked at, for the byte-level (passive) checks."""

    n: int
    message: str | None
    problem: str | None
    clause: str | None
    t: float
    undecided: bool = False  # ``problem`` says why the frame was not judged, not what it breaks


@dataclass
class StepState:
    spec: dict
    kind: str
    until: float | None = None
    tries: int = 1
    replies: list = field(default_factory=list)
    malformed: int = 0
    unjudged: int = 0  # frames of the awaited message the suite could not judge
    terminal: Parsed | None = None
    failures: dict = field(default_factory=dict)  # check -> first detail
    unmatched: str = ""  # the first reply whose echoed value was not the request's (it is not this step's)
    unmatched_count: int = 0
    misechoed: tuple | None = None  # (echo rule, what it echoed) of a reply to this scenario's entity echoing wrongly
    bound: float | None = None  # when the step's own time is up (a quiet period after a terminal state may move until)
    open_end: str | None = None  # the ambiguity id when the sequence's last state is one the seeds leave open
    readings: dict = field(default_factory=dict)  # ambiguity id -> what the node did that the seeds leave open
    silences: set = field(default_factory=set)  # the readings among them that are a request's silence
    states: tuple = ()  # (the States of its replies, or None), once worked out
    seen: set = field(default_factory=set)  # what it took, to tell the link's byte-identical copies


def step_length(spec: dict):
    """How long a waiting step lasts, in seconds of the scenario (before --time-scale)."""
    return spec.get("within", spec.get("for", spec.get("wait")))
