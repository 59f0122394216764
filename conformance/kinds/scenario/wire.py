"""What a suite gives the scenario engine: how to build what a step sends and read what comes back.

The engine is generic: it never looks inside a frame. A suite's ``Wire`` composes a step's message (with
the run's addressing) into the bytes (or call) to send, and says which transport it rides, parses what arrives into a ``Parsed``, resolves
the names a scenario uses for values (enumerations), and tells who sent a reply and to whom.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Protocol


@dataclass(frozen=True)
class Addressing:
    """Who talks: the session (``system``, and one ``entity`` per scenario, so replies can be told apart), the
    session's second system on the link (``other``: a second client, for steps sent ``as`` it), the node
    (``node``; None until learned), a system the session never announces (``stranger``: a sender the node has
    never heard of, for a step's header) and one it announces only once a step has spoken as it (``late``: a system
    that appears on the link during a scenario). Suites without addresses leave them None."""

    system: int | None = None
    entity: int | None = None
    node: int | None = None
    other: int | None = None
    stranger: int | None = None
    late: int | None = None

    def speaking_as(self, who: str | None) -> "Addressing":
        """The addressing a step sends with: the session's (``who`` None), its second system's (``"other"``) or
        the system that appears late (``"late"``)."""
        if who == "late":
            return replace(self, system=self.late)
        return self if who is None else replace(self, system=self.other, other=self.system)

    def for_entity(self, entity: int | None) -> "Addressing":
        return replace(self, entity=entity)

    def symbols(self) -> dict:
        """What ``{"$address": NAME}`` resolves to."""
        return {"system": self.system, "node": self.node, "other": self.other, "stranger": self.stranger,
                "late": self.late}

    def from_node(self, wire, parsed) -> bool:
        """Whether something arrived from the node (true where the protocol has no addresses, or the node's id is
        not known yet)."""
        origin = wire.origin(parsed)
        return origin is None or self.node is None or origin[0] == self.node


@dataclass(frozen=True)
class Parsed:
    """One thing received. ``message``: its message name when known, even from a malformed frame's header;
    ``decoded``: its decoded form (``fields``, and ``header`` where the protocol has one) if well formed;
    ``problem`` and ``clause``: why it is malformed and the rule it breaks; ``undecided``: ``problem`` says why
    the suite could not judge it (a bound it keeps), not what it breaks; ``addressed``: (system, entity) a frame
    that did not decode is addressed to, where its header could still be read. ``outside``: a sound frame (its
    framing checked) of a message outside the suite's definitions, named (its name or id): judged no further, only
    counted; ``undefined``: no definition the suite has names its id at all (a node on a newer protocol)."""

    data: object
    message: str | None
    decoded: dict | None = None
    problem: str | None = None
    clause: str | None = None
    encoding: str | None = None
    undecided: bool = False
    addressed: tuple | None = None
    outside: str | None = None
    undefined: bool = False

    @property
    def fields(self) -> dict:
        return (self.decoded or {}).get("fields", {})


@dataclass(frozen=True)
class Composed:
    """What a send step sends (``data``) and its decoded form, for the timeline and for later references."""

    data: object
    decoded: dict
    message: str
    encoding: str | None = None
    extra: dict = field(default_factory=dict)


class Wire(Protocol):
    transport: str  # "datagram" (a live target, --target) or "call" (a handler called through an adapter)
    anyone: int | None  # the destination meaning any system (a request to it is for the node too), or None

    def compose(self, message: dict, encoding: str | None, addressing: Addressing, epoch: float,
                step: str = "", edition: str | None = None) -> Composed:
        """The message (decoded form, values resolved) as sent by the session at ``epoch`` (seconds since
        1970) for send step ``step``, in ``edition``; raises ValueError if it cannot be built."""

    def setup(self, service: str, state: dict, step: str) -> Composed:
        """(call transports) The call that prepares a handler's state for setup step ``step``."""

    def reply(self, composed: Composed, answer) -> Parsed | None:
        """(call transports) What a call's answer delivers to the scenario (a response), or None (a publish
        or a setup, which only acknowledge)."""

    def knows(self, message: str) -> bool:
        """Whether the suite has the message."""

    def fields_of(self, message: str) -> list[str]:
        """Its field names (in any edition)."""

    def example(self, message: str, edition: str) -> dict:
        """The fields of a message with default values (what a reply is assumed to hold when scenarios are
        checked before a run)."""

    def parse(self, data) -> Parsed:
        """What arrived, parsed."""

    def resolve(self, message: str, path: str, value, edition: str):
        """``value`` for field ``path`` of ``message`` with names (enumeration values) turned into what the
        wire carries; raises KeyError for a name the edition lacks."""

    def size_of(self, message: str, path: str, value) -> int:
        """How many bytes field ``path`` of ``message`` takes on the wire holding ``value``."""

    def origin(self, parsed: Parsed) -> tuple | None:
        """(system, entity) that sent it, or None where the protocol has no addresses."""

    def destination(self, parsed: Parsed) -> tuple | None:
        """(system, entity) it is addressed to, or None."""

    def present(self, parsed: Parsed | Composed) -> dict:
        """A timeline entry's description of it: ``message``, ``header``, ``fields`` (names for numbers where
        the definitions give them), ``bytes``."""
