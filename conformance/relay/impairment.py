"""A link that fails like the sea's, sans-IO: what becomes of each datagram one direction of the relay carries, on
virtual time. Every draw comes from a generator seeded by the run's seed and the direction's name, so the same
datagrams at the same times meet the same fate."""

from __future__ import annotations

import random
from dataclasses import asdict, dataclass, field

DISTRIBUTIONS = ("uniform", "normal", "exponential")
DUPLICATE_GAP = 0.001  # s between a datagram and its copy
QUEUE_LIMIT = 1 << 16  # bytes a capped link holds waiting to be sent; beyond that it drops (a full buffer)


@dataclass(frozen=True)
class Impairment:
    """What one direction does to its datagrams. ``loss``: the share dropped; ``burst``: the mean length of a run of
    losses (Gilbert-Elliott; 0: each datagram drawn alone); ``delay``: seconds added to every datagram, plus a draw of
    ``jitter`` seconds from ``distribution``; ``duplicate``: the share sent twice; ``reorder``: the share held back
    ``hold`` seconds (the ones after it overtake it); ``corrupt``: the share with one byte changed; ``rate``: bits per
    second (0, the default: no cap; ``parse`` refuses rate=0 given); ``down``: windows (start, end) in seconds from
    the relay's start when nothing passes."""

    loss: float = 0.0
    burst: float = 0.0
    delay: float = 0.0
    jitter: float = 0.0
    distribution: str = "uniform"
    duplicate: float = 0.0
    reorder: float = 0.0
    hold: float = 0.2
    corrupt: float = 0.0
    rate: float = 0.0
    down: tuple[tuple[float, float], ...] = ()

    @property
    def none(self) -> bool:
        return self == Impairment()

    @property
    def usual(self) -> float:
        """The most this link usually adds to a datagram's way (its delay, a hold, a uniform jitter): a datagram held
        longer (an unbounded jitter's tail, a capped link's queue) is held beyond the usual."""
        return self.delay + (self.hold if self.reorder else 0.0) + (self.jitter if self.distribution == "uniform" else 0.0)

    def describe(self) -> dict:
        """What the provenance records: the settings that differ from a clean link."""
        clean = asdict(Impairment())
        return {k: ([list(w) for w in v] if k == "down" else v) for k, v in asdict(self).items() if v != clean[k]}


SHARES = ("loss", "duplicate", "reorder", "corrupt")
SECONDS = ("burst", "delay", "jitter", "hold", "rate")


def parse(text: str) -> Impairment:
    """``loss=0.3,burst=3,delay=2,jitter=0.5,distribution=normal,duplicate=0.01,reorder=0.05,corrupt=0.01,
    rate=9600,down=30-40+90-95``; ValueError with a one-line reason."""
    values: dict = {}
    for item in filter(None, (part.strip() for part in text.split(","))):
        key, sep, value = item.partition("=")
        if not sep or key not in Impairment.__dataclass_fields__:
            raise ValueError(f"{item!r}: expected NAME=VALUE with NAME one of {', '.join(Impairment.__dataclass_fields__)}")
        if key in values:
            raise ValueError(f"{key} given twice")
        if key == "distribution":
            if value not in DISTRIBUTIONS:
                raise ValueError(f"distribution={value!r}: one of {', '.join(DISTRIBUTIONS)}")
            values[key] = value
        elif key == "down":
            values[key] = tuple(_window(w) for w in value.split("+"))
        else:
            try:
                number = float(value)
            except ValueError:
                raise ValueError(f"{key}={value!r}: not a number") from None
            if not number == number or number < 0 or (key in SHARES and number >= 1) or number > 1e6:
                raise ValueError(f"{key}={value!r}: " + ("a share in [0, 1)" if key in SHARES else "a number in [0, 1e6]"))
            if key == "rate" and number == 0:
                raise ValueError("rate=0: a cap in bits per second above 0 (leave rate out for a link with no cap)")
            if key == "burst" and 0 < number < 1:
                raise ValueError(f"burst={value!r}: a mean run of losses is 1 datagram or more (0: none)")
            values[key] = number
    if values.get("burst") and not values.get("loss"):
        raise ValueError("burst needs a loss rate (loss=...)")
    return Impairment(**values)


def _window(text: str) -> tuple[float, float]:
    start, sep, end = text.partition("-")
    try:
        window = (float(start), float(end))
    except ValueError:
        window = None
    if not sep or window is None or not 0 <= window[0] < window[1] <= 1e6:
        raise ValueError(f"down={text!r}: expected START-END in seconds from the start, START < END")
    return window


@dataclass(slots=True)
class Fate:
    """What became of a datagram: copies delivered (arrival time, bytes, what was done to them) or why none was."""

    copies: list[tuple[float, bytes, str]] = field(default_factory=list)
    dropped: str | None = None


class Link:
    """One direction of the relay. ``carry(t, data)`` says when and how the datagram sent at ``t`` arrives."""

    def __init__(self, impairment: Impairment, seed: int, name: str):
        self.impairment, self.name = impairment, name
        self.rng = random.Random(f"{seed}/{name}")
        self.bad = False  # the loss model's state (bursts)
        self.free_at = 0.0  # when a capped link has sent what it holds
        self.start: float | None = None  # the relay's start, the origin of ``down``

    def carry(self, t: float, data: bytes) -> Fate:
        imp, rng = self.impairment, self.rng
        if self.start is None:
            self.start = t
        draws = [rng.random() for _ in range(6)]  # as many draws each datagram, whatever befalls it
        if any(a <= t - self.start < b for a, b in imp.down):
            return Fate(dropped="the link was down")
        if self._lost(draws[0]):
            return Fate(dropped="lost (loss)")
        when, what = t + imp.delay, []
        if imp.rate:
            begin = max(t, self.free_at)
            if (begin - t) * imp.rate / 8 > QUEUE_LIMIT:
                return Fate(dropped=f"the capped link's queue was full ({QUEUE_LIMIT} bytes)")
            self.free_at = begin + len(data) * 8 / imp.rate
            when += self.free_at - t
        if imp.jitter:
            when += self._jitter(rng)
        if draws[1] < imp.reorder:
            when += imp.hold
            what.append(f"held {imp.hold:g} s")
        if draws[2] < imp.corrupt and data:
            position = int(draws[3] * len(data))
            data = data[:position] + bytes([data[position] ^ (1 + int(draws[4] * 255))]) + data[position + 1:]
            what.append(f"byte {position} changed")
        note = ", ".join(what)
        copies = [(when, data, note)]
        if draws[5] < imp.duplicate:
            copies.append((when + DUPLICATE_GAP, data, (note + ", " if note else "") + "duplicated"))
        return Fate(copies)

    def _lost(self, draw: float) -> bool:
        imp = self.impairment
        if not imp.loss:
            return False
        if not imp.burst:
            return draw < imp.loss
        # Gilbert-Elliott with every datagram lost in the bad state: leave it after a mean of ``burst`` datagrams,
        # enter it so that the share of time in it is ``loss``
        leave = 1.0 / imp.burst
        enter = imp.loss * leave / (1.0 - imp.loss)
        self.bad = draw >= leave if self.bad else draw < enter
        return self.bad

    def _jitter(self, rng: random.Random) -> float:
        imp = self.impairment
        if imp.distribution == "normal":
            return abs(rng.gauss(0.0, imp.jitter))
        if imp.distribution == "exponential":
            return rng.expovariate(1.0 / imp.jitter)
        return rng.uniform(0.0, imp.jitter)
