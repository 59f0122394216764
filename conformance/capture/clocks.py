"""The clocks of a log. A log holds frames stamped by several systems' clocks (the logging system's own, a console's,
another vehicle's relayed to it, an acoustic peer's), in the order the logging system logged them: the order of
arrival. One clock times the log, the logging system's (the system that stamped most of its first ``CHOOSE``
frames). Its own frames are timed by their stamps; any other frame (another system's, one with no time, one of its
own stamped off its clock) by its place: it was logged after the logging system's frames before it and before the
next one, so at the earliest at the latest stamp before it and at the latest at the stamp after it plus
``CLOCK_BACK`` (a frame is logged up to that long after its system stamps it). Exchanges are timed by these
brackets (``Watched.latest``): a reply PASSes when it came within its bound at the latest, a request FAILs
unanswered when its bound has passed from its latest time, and only what lies between is INCONCLUSIVE, whatever the
offset between the clocks.

The logging system's clock jumps where its frames run on, for ``CONFIRM`` seconds, from a stamp more than
``CLOCK_JUMP`` ahead of its clock or ``CLOCK_BACK`` behind it (a gap in the log, its clock set), none back on the
clock meanwhile: the log is split there into stretches timed apart. Frames stamped off the clock that its next frames
contradict (a message kept with the time it was first made, a burst stamped alike) are timed by their place. Before
a split every exchange whose bound passed while the clock ran is decided; one open across it is INCONCLUSIVE.
Sans-IO: the judge feeds the frames' stamps and watched frames, and takes the frames back, timed, through
``observe``."""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable

from .findings import Watched

CLOCK_JUMP = 10.0  # seconds the logging system's clock may leap ahead between two of its frames (a log's gap)
CLOCK_BACK = 1.0  # seconds a frame may be stamped behind the clock (logged after a later-stamped one: DUNE's, 0.15 s)
CONFIRM = 1.0  # seconds the logging system's frames run on a new clock before it is taken as a jump
MAX_TIME = 1e11  # seconds since the epoch: a stamp beyond (or not a number) is no time
CHOOSE = 1000  # first frames of a log the logging system is chosen among
CHOOSE_BYTES = 8 << 20  # bytes of those frames at most (they are held until it is chosen)
HELD = 1024  # watched frames held for the end of their bracket at most (beyond, their latest time is unknown)
NEVER = float("inf")
LISTED = 8  # other systems named in a note


class LogClocks:
    """The clocks of one log (several files judged at once are one log): its exchanges followed by ``tracker``
    (``next_deadline`` read, to call ``due`` only when something is due); ``observe`` takes a watched frame once
    timed, ``due`` judges the exchanges whose bound passed by a time, ``split`` closes the exchanges open at a jump."""

    def __init__(self, tracker, observe: Callable[[Watched], None], due: Callable[[float], None],
                 split: Callable[[], None]):
        self.tracker, self.observe, self.due, self.split = tracker, observe, due, split
        self.own: object = None  # the logging system (None: the format names no system, or none was seen)
        self.now = 0.0  # its clock: the latest stamp of its frames on it
        self.origin: float | None = None
        self.exact = True  # the last frame ticked is timed by its own stamp
        self.running: float | None = None  # the last frame's stamp, where it runs on the candidate clock
        self.candidate: list | None = None  # [first stamp, latest stamp, frames]: the logging system's frames off
        # its clock, running together (a jump, once they have run CONFIRM seconds; else frames timed by their place)
        self.held: list[tuple[Watched, float | None]] = []  # watched frames waiting for the end of their bracket,
        # each with its stamp where it is the logging system's, on the candidate clock
        self.at = 0  # the held frames before the candidate's first
        self.jumps = 0
        self.off_clock = 0  # the logging system's frames stamped off its clock, timed by their place
        self.untimed = 0  # frames with no time
        self.others: dict = {}  # system -> [frames, least and greatest stamp less the clock]

    def choose(self, frames: list) -> None:
        """Choose the logging system among a log's first frames (``Logged``): the one that stamped most of them."""
        if not frames:
            return
        self.own = Counter(f.system for f in frames).most_common(1)[0][0]
        own = [f.time for f in frames if f.system == self.own and _timed(f.time)]
        self.origin = self.now = (own or [f.time for f in frames if _timed(f.time)] or [0.0])[0]
        if own and not (frames[0].system == self.own and _timed(frames[0].time)):
            self.now = -NEVER  # the frames before its first came at any time before it

    def tick(self, system, stamp: float) -> float:
        """The time on the log's clock of the next frame (from ``system``, stamped ``stamp``): its stamp, or for a
        frame timed by its place, the earliest (its bracket is closed by the logging system's next frame). Runs the
        clock: closes the brackets open, judges what is due, splits the log at a jump."""
        now = self.now
        if system == self.own and now - CLOCK_BACK <= stamp <= now + CLOCK_JUMP:  # the logging system's, on its clock
            if self.candidate is not None:  # the frames off it were no jump
                self.off_clock += self.candidate[2]
                self.candidate = None
            self.exact = True
            if self.held:
                self._close(stamp + CLOCK_BACK)
            if stamp > now:
                self.now = stamp
                if stamp - CLOCK_BACK > self.tracker.next_deadline:
                    self.due(stamp - CLOCK_BACK)  # a frame stamped up to CLOCK_BACK behind may still answer
            return stamp
        self.exact, self.running = False, None
        if now == -NEVER and system == self.own and _timed(stamp):  # its first frame: the clock starts
            self.now, self.exact = stamp, True
            if self.held:
                self._close(stamp + CLOCK_BACK)
            return stamp
        if system != self.own or not _timed(stamp):
            if not _timed(stamp):
                self.untimed += 1
            elif now != -NEVER:
                other = self.others.get(system)
                if other is None:
                    self.others[system] = [1, stamp - now, stamp - now]
                else:
                    other[0] += 1
                    other[1], other[2] = min(other[1], stamp - now), max(other[2], stamp - now)
            return now
        c = self.candidate
        if c is not None and c[1] - CLOCK_BACK <= stamp <= c[1] + CLOCK_JUMP:  # running on with the frames off it
            c[1], c[2] = max(c[1], stamp), c[2] + 1
            if c[1] - c[0] >= CONFIRM:
                self._jump(stamp)
                self.exact = True
                return stamp
        else:
            if c is not None:
                self.off_clock += c[2]
            self.candidate, self.at = [stamp, stamp, 1], len(self.held)
        self.running = stamp
        return now

    def watch(self, w: Watched) -> None:
        """A watched frame, the one last ticked (``w.time`` the time ``tick`` gave): to the exchanges at once if
        timed by its stamp, else once its bracket is closed."""
        if self.exact and not self.held:
            self.observe(w)
            return
        self.held.append((w, None if self.exact else self.running))
        if len(self.held) > HELD:
            self._close(NEVER)

    def end(self) -> None:
        """The log ended: the frames held are timed with no latest time (the log says nothing after them)."""
        if self.candidate is not None:
            self.off_clock += self.candidate[2]
            self.candidate = None
        self._close(NEVER)

    def _close(self, latest: float) -> None:
        """The logging system's clock reached ``latest``: every frame held was logged by then."""
        held, self.held, self.at = self.held, [], 0
        for w, _ in held:
            w.latest = latest
            self.observe(w)

    def _jump(self, stamp: float) -> None:
        """The frames off the clock ran on for CONFIRM seconds with ``stamp``: the clock jumped at the first of them.
        What came before is decided by the old clock, or open across the split; what came after is timed anew."""
        c, held, at = self.candidate, self.held, self.at
        self.candidate, self.held, self.at = None, [], 0
        for w, _ in held[:at]:
            w.latest = NEVER
            self.observe(w)
        if self.now > self.tracker.next_deadline:
            self.due(self.now)
        self.split()
        self.jumps += 1
        now = c[0]
        for w, own in held[at:]:
            if own is not None:
                w.time, w.latest = own, None
                now = max(now, own)
            else:
                w.time, w.latest = now, stamp + CLOCK_BACK
            self.observe(w)
        self.now = c[1]

    def notes(self) -> list[str]:
        """What a report says of the log's clocks."""
        out = []
        if self.others:
            named = sorted(self.others.items(), key=lambda kv: -kv[1][0])
            listed = ", ".join(f"{system} ({n:,} frame{'s' if n != 1 else ''}, {_offset(low, high)})"
                               for system, (n, low, high) in named[:LISTED])
            more = f", and {len(named) - LISTED} more" if len(named) > LISTED else ""
            out.append(f"the log is timed by the clock of system {self.own}, which stamped most of its first frames; "
                       f"the frames of {len(named)} other system{'s' if len(named) != 1 else ''} by their place between "
                       "its frames (the log's order is the order of arrival), whatever their own clocks: "
                       f"{listed}{more}")
        if self.off_clock:
            out.append(f"{self.off_clock:,} frame{'s' if self.off_clock != 1 else ''} of the logging system stamped "
                       f"off its clock (more than {CLOCK_JUMP:g} s ahead or {CLOCK_BACK:g} s behind, its next frames "
                       "back on it: a message kept with the time it was first made, a burst stamped alike): timed by "
                       "their place in the log")
        if self.untimed:
            out.append(f"{self.untimed:,} frame{'s' if self.untimed != 1 else ''} with no time (not a number, or "
                       "beyond any date): timed by their place in the log")
        return out


def _timed(t: float) -> bool:
    return -MAX_TIME < t < MAX_TIME


def _offset(low: float, high: float) -> str:
    """How a system's stamps stood against the log's clock when its frames came (``low`` to ``high`` seconds ahead)."""
    shown = [f"{abs(v):.1f}" for v in (low, high)]
    if shown[0] == shown[1] and (low < 0) == (high < 0):
        return f"stamped {shown[0]} s {'behind' if low < 0 else 'ahead'}"
    if high < 0:
        return f"stamped {shown[1]} to {shown[0]} s behind"
    if low >= 0:
        return f"stamped {shown[0]} to {shown[1]} s ahead"
    return f"stamped from {shown[0]} s behind to {shown[1]} s ahead"
