"""The robustness phase, sans-IO: the target receives every frame of the corpus, then the traffic UDP brings every
day, then a burst of garbage, and must still answer every request kind it answered before.

One machine runs the phase for every robustness case of the run (a batch): each case is a *probe*, a request
kind and the reply that shows it is still served. The machine probes each once (baseline), sends the corpus
frames in blocks (paced, readdressed to come from the session and go to the target, each case's defect kept),
probes after each block, sends the hostile blocks (the probes' own requests addressed to anyone, to 0 or to another
system, from the node's own id or from a system never announced, duplicated, reusing one id, many at once: the
settings' ``hostile``) and probes after each, sends the garbage, probes again; a probe that goes unanswered names the
block that silenced it, and when the session can restart the target a corpus block is bisected down to the frame
that does it (a hostile block is named as it is: its kind is the finding). A probe's reply is known by the values it
echoes, or by its addressee, the probe's own entity: the replies to the floods (another entity, other systems, other
ids) are never taken for it.
It is written as a generator that yields what it needs (send a frame, wait for a reply or a time, restart the
target) so the sequence reads top to bottom; the driver below turns events into resumptions.
"""

from __future__ import annotations

import random
from dataclasses import dataclass, field

from ..scenario.wire import Addressing, Composed, Parsed
from .hostile import Hostile
from .probing import Probing
from .script import FLOOD_ENTITY, Frame, Probe, Restart, Send, Wait
from ...core.wording import counted


@dataclass
class Phase:
    """What every probe of one run shares: the frames, the settings (exchanges.json ``robustness``), the wire,
    the exchange rules, the run's parameters and time scale, and whether the session can restart the target."""

    frames: list[Frame]
    skipped: list[str]  # why frames were left out (too large for a datagram, effects not allowed)
    settings: dict
    wire: object
    exchanges: tuple
    edition: str
    params: dict
    time_scale: float = 1.0
    can_restart: bool = False
    bounds: dict = field(default_factory=dict)  # the suite's timing bounds, which probes name

    def machine(self, addressing: Addressing, unique, members) -> "PhaseMachine":
        return PhaseMachine(self, list(members), addressing, unique)


@dataclass(frozen=True)
class ProbeProgram:
    """One robustness case as a program of the phase's batch."""

    case_id: str
    case: dict
    phase: Phase
    exclusive: bool = True

    @property
    def batch(self) -> Phase:
        return self.phase

    @property
    def wire(self):
        return self.phase.wire

    @property
    def edition(self) -> str:
        return self.phase.edition

    @property
    def params(self) -> dict:
        return self.phase.params

    @property
    def scenario(self) -> dict:
        """The probe as the scenario it amounts to (what ``--dry-run`` shows)."""
        return as_scenario(self.case)

    def resources(self) -> set[str]:
        return {"*"}

    def machine(self, addressing: Addressing, unique, members) -> "PhaseMachine":
        return self.phase.machine(addressing, unique, members)


def as_scenario(case: dict) -> dict:
    """A robustness probe as the scenario it amounts to (send, then expect the reply; or alive), for the lint."""
    probe = case["probe"]
    if "alive" in probe:
        steps = [{"id": "alive", "alive": probe["alive"], "within": probe["within"]}]
    else:
        steps = [{"id": "probe", "send": probe["send"], "encoding": probe.get("encoding", "le")},
                 {"id": "reply", "expect": probe["expect"], "reply_to": "probe", "within": probe["within"]}
                 | ({"queued": probe["queued"]} if "queued" in probe else {})]
    if "covers" in case:
        steps[-1]["covers"] = case["covers"]
    return dict(case, steps=steps)


class PhaseMachine(Probing, Hostile):
    """The phase for every robustness case of the run: the session's events in, frames to send out, each probe's
    findings kept."""

    def __init__(self, phase: Phase, members: list[ProbeProgram], addressing: Addressing, unique):
        self.phase, self.addressing, self.unique = phase, addressing, unique
        self.probes = [Probe(m) for m in members]
        self.wire = phase.wire
        self.keys: list = []
        self.keys_seen = 0
        self.timeline: list[dict] = []
        self.frames_seen: list[dict] = []  # malformed frames the target sent (capped)
        self.malformed = 0
        self.t0 = self.now = 0.0
        self.epoch = 0.0
        self.done = False
        self.restart_wanted = False
        self.waiting: Wait | None = None
        self.impairments: list[str] = []  # what the link could not show, in order
        self.replayed: list[Frame] = []  # the frames replayed since the last round (a queueing node works them off)
        self.requests_in: dict[bytes, str | None] = {}  # a replayed frame -> the exchange it opens as a request
        self._script = None

    # ------------------------------------------------------------------ driving the script

    def start(self, t: float, epoch: float) -> list[Composed]:
        self.t0 = t
        self._script = self._run()
        return self._resume(t, epoch, None)

    @property
    def deadline(self) -> float | None:
        return None if self.done or self.waiting is None else self.waiting.until

    def watches(self, parsed: Parsed) -> bool:
        return False  # it claims nothing: a reply reaches it only by its echoed keys or its entity, or unowned

    def deliver(self, t: float, epoch: float, parsed: Parsed, adopt: bool = False) -> list[Composed]:
        if self.done:
            return []
        if parsed.problem is not None:
            self.malformed += not parsed.undecided
            if len(self.frames_seen) < self.phase.settings.get("malformed_listed", 20):
                self.frames_seen.append({"n": len(self.frames_seen) + 1, "message": parsed.message,
                                         "problem": parsed.problem, "clause": parsed.clause, "t": self._rel(t),
                                         "undecided": parsed.undecided})
        if self.waiting is not None and self.waiting.accepts is not None and parsed.decoded is not None \
                and self.waiting.accepts(parsed):
            return self._resume(t, epoch, parsed)
        return []

    def wake(self, t: float, epoch: float) -> list[Composed]:
        if self.done or self.waiting is None or t < self.waiting.until:
            return []
        return self._resume(t, epoch, None)

    def impaired(self, t: float, why: str, lasting: bool = False) -> None:
        """The link could not show everything (``why``): a probe unanswered in the round under way is not judged."""
        self.impairments.append(why)
        self._log("impaired", why)

    def cannot_run(self, t: float, why: str) -> None:
        """The session could not send what the phase sent: every probe is untested (not the node's fault)."""
        for probe in self.probes:
            probe.error = probe.error or why
        self._log("stopped", why)
        self.done, self.waiting = True, None

    def restarted(self, t: float, epoch: float, problem: str | None) -> list[Composed]:
        self.restart_wanted = False
        return self._resume(t, epoch, problem)

    def _resume(self, t: float, epoch: float, value) -> list[Composed]:
        self.now, self.epoch, self.waiting = t, epoch, None
        out = []
        try:
            while True:
                item = self._script.send(value)
                value = None
                if isinstance(item, Send):
                    out.append(item.composed)
                elif isinstance(item, Wait):
                    self.waiting = item
                    return out
                else:
                    self.restart_wanted = True
                    return out
        except StopIteration:
            self.done = True
        return out

    # ------------------------------------------------------------------ the phase, top to bottom

    def _run(self):
        settings, phase = self.phase.settings, self.phase
        self._log("phase", f"{counted(len(phase.frames), 'corpus frame')} in blocks of {settings['block']}, then "
                           f"{counted(settings['garbage'], 'garbage datagram')}; {counted(len(self.probes), 'probe')}"
                  + "".join(f"; skipped {why}" for why in phase.skipped))
        unanswered = yield from self._round(self.probes, "baseline")
        for probe in self.probes:
            probe.baseline = probe not in unanswered
        blocks = [phase.frames[i:i + settings["block"]] for i in range(0, len(phase.frames), settings["block"])]
        restarted = False
        for k, block in enumerate(blocks, 1):
            if not self._listening():
                why = "every probe is silenced" if any(p.baseline for p in self.probes) else "no probe was answered before"
                self._log("phase", f"{why}: blocks {k} to {len(blocks)} not sent")
                break
            yield from self._replay(block)
            self._log("block", f"block {k} of {len(blocks)} sent: {_span(block)}")
            silenced = yield from self._round(self._listening(), f"after block {k}")
            for probe in silenced:
                probe.down = True
                probe.silencings.append(f"block {k} of {len(blocks)} ({_span(block)})")
            if silenced and self.phase.can_restart:  # find the frame, bring the node back, and go on
                found = yield from self._bisect(block, silenced)
                for probe in silenced:
                    probe.silencings[-1] += f"; {found}"
                restarted = True
                if not (yield from self._revive(silenced)):
                    break
            elif silenced:
                for probe in silenced:
                    probe.silencings[-1] += "; give --restart-cmd to bisect to the frame"
        for name, frames in self._hostile():
            if not self._listening():
                break
            yield from self._replay(frames)
            self._log("block", f"hostile block {name} sent: {len(frames)} frames")
            asked = self._listening()
            silenced = yield from self._round(asked, f"after the hostile block {name}")
            for probe in asked:
                probe.hostile_run += 1
            for probe in silenced:
                probe.down = True
                probe.hostile.append(f"{name} ({len(frames)} frames)")
            if silenced and self.phase.can_restart:
                restarted = True
                if not (yield from self._revive(silenced)):
                    break
        if self._listening():
            rng = random.Random(settings["seed"])
            source = (self.addressing.system, FLOOD_ENTITY)
            for data in self.wire.garbage(rng, settings["garbage"], source, self._node()):
                yield Send(Composed(data, {}, "", None))
                yield Wait(self.now + self._scaled(settings["garbage_pace"]))
            yield Wait(self.now + self._scaled(settings["settle"]))
            self._log("garbage", f"{settings['garbage']} garbage datagrams sent (seed {settings['seed']})")
            for probe in (yield from self._round(self._listening(), "after the garbage")):
                probe.down, probe.garbage = True, f"the {settings['garbage']} garbage datagrams"
        if self.phase.can_restart and (restarted or any(p.down for p in self.probes)):
            problem = yield Restart()  # leave the target as it was found
            self._log("restart", "restarted to leave the target running" if problem is None else problem)

    def _revive(self, probes: list[Probe]):
        """Restart the node after a bisection; whether the probes are served again (else the phase stops)."""
        problem = yield Restart()
        if problem is None and (yield from self._round(probes, "after a restart, before going on", self._revival())):
            problem = "after a restart the node did not serve the probe again"
        if problem is not None:
            self._log("restart", f"the phase stops: {problem}")
            return False
        for probe in probes:
            probe.down = False
        return True

    def _listening(self) -> list[Probe]:
        return [p for p in self.probes if p.baseline and not p.down and not p.error]

    def _replay(self, frames: list[Frame]):
        pace, source = self._scaled(self.phase.settings["pace"]), (self.addressing.system, FLOOD_ENTITY)
        for frame in frames:
            data = frame.data if frame.addressed else self.wire.readdress(frame.data, frame.encoding, source, self._node())
            yield Send(Composed(data, {}, "", frame.encoding))
            yield Wait(self.now + pace)
        self.replayed = frames
        yield Wait(self.now + self._scaled(self.phase.settings["settle"]))

    def _bisect(self, block: list[Frame], probes: list[Probe]):
        """Restart, replay half of the block, probe; keep the half that silences a probe, down to one frame; what
        it found."""
        candidates = block
        while True:
            problem = yield Restart()
            if problem is None and (yield from self._round(probes, "after a restart, before bisecting further",
                                                           self._revival())):
                problem = "after a restart the node did not serve the probe again"
            if problem is not None:
                self._log("restart", f"cannot bisect: {problem}")
                return f"not bisected: {problem}"
            half = candidates[:max(1, len(candidates) // 2)] if len(candidates) > 1 else candidates
            yield from self._replay(half)
            silent = bool((yield from self._round(probes, f"bisecting: after {_span(half)}")))
            if len(candidates) == 1:
                what = (f"bisected: the frame {_name(half[0])} alone silences it" if silent else
                        f"not reproduced by a single frame: the last candidate, {_name(half[0])}, did not silence "
                        f"it alone (several frames together do, or the node's state at the time did)")
                self._log("bisect", what)
                return what
            candidates = half if silent else candidates[len(half):]

    def _node(self) -> int:
        return 0xFFFF if self.addressing.node is None else self.addressing.node

    # ------------------------------------------------------------------ what it found

    def record(self, member: int) -> dict:
        probe = self.probes[member]
        case = probe.program.case
        clause, level = case["clause"], case.get("level", "MUST")
        what = case["probe"].get("expect") or case["probe"].get("alive") or "a frame"
        if probe.error:
            findings = []
        elif not probe.baseline:
            findings = [{"check": "probe:baseline", "passed": False, "inconclusive": True, "level": level, "clause": clause,
                         "detail": f"no {what} before the robustness phase either: its scenarios judge that; whether "
                                   "the target survives the corpus cannot be told from this probe"}]
        else:
            findings = [{"check": "probe:baseline", "passed": True, "level": level, "clause": clause,
                         "detail": f"{what} received before the robustness phase"}]
            skipped = f" ({'; '.join(self.phase.skipped)} left out)" if self.phase.skipped else ""
            blocks = -(-len(self.phase.frames) // self.phase.settings["block"])
            detail = (f"no {what} after " + "; and after ".join(probe.silencings) if probe.silencings else
                      f"{what} still received after each of the {blocks} blocks ({len(self.phase.frames)} corpus frames)"
                      f"{skipped}")
            findings.append({"check": "probe:corpus", "passed": not probe.silencings, "level": level, "clause": clause,
                             "detail": detail})
            if probe.hostile_run:
                findings.append({"check": "probe:hostile", "passed": not probe.hostile, "level": level, "clause": clause,
                                 "detail": f"no {what} after the hostile block " + "; and after ".join(probe.hostile)
                                 if probe.hostile else f"{what} still received after each of the {probe.hostile_run} "
                                 "hostile blocks (requests addressed elsewhere, from the node's own id or an unannounced "
                                 "system, duplicated, reusing one id, many at once)"})
            if not probe.down or probe.garbage:
                findings.append({"check": "probe:garbage", "passed": probe.garbage is None, "level": level,
                                 "clause": clause, "detail": f"no {what} after {probe.garbage}" if probe.garbage
                                 else f"{what} still received after the garbage burst"})
            if probe.blind:
                findings.append({"check": "probe:link", "passed": False, "inconclusive": True, "level": level,
                                 "clause": clause, "detail": f"no {what} in a round the link could not show whole, "
                                                             f"so not judged ({probe.blind})"})
        timeline = [e for e in self.timeline if e.get("probe") in (None, member)]
        return {"findings": findings, "timeline": [{k: v for k, v in e.items() if k != "probe"} for e in timeline],
                "frames": self.frames_seen if member == 0 else [], "error": probe.error}

    def _log(self, event: str, note: str, probe: Probe | None = None) -> None:
        entry = {"t": self._rel(self.now), "event": event, "note": note}
        if probe is not None:
            entry["probe"] = self.probes.index(probe)
        self.timeline.append(entry)

    def _rel(self, t: float) -> float:
        return round(t - self.t0, 3)

    def _revival(self) -> float:
        """How long a restarted node is given to serve the probes again."""
        return self._scaled(self.phase.settings["revive"])

    def _scaled(self, seconds: float) -> float:
        return float(seconds) * self.phase.time_scale


def _name(frame: Frame) -> str:
    return f"{frame.case_id} ({frame.encoding}, {frame.expect})"


def _span(frames: list[Frame]) -> str:
    if len(frames) == 1:
        return _name(frames[0])
    return f"{len(frames)} frames, {_name(frames[0])} to {_name(frames[-1])}"
