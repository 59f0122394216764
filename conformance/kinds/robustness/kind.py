"""Sans-IO planning and judging of robustness cases (``--robustness``), a case kind of the core.

A robustness case is a probe: a request kind of the target and the reply that shows it is served (or a
message that shows it is alive). The kind plans every admitted probe of a run into one shared phase (the
corpus frames of the edition, replayed, then garbage), which the session runs as a batch; each probe gets its
own verdict, filed under its request's message: INCONCLUSIVE if it was not answered before the phase, FAIL if
it stopped being answered, naming the block and, when the target can be restarted, the frame that did it.
"""

from __future__ import annotations

from ...core.cases import expectation
from ..scenario.kind import LiveKind
from .phase import Frame, Phase, ProbeProgram
from ...core.wording import counted


class RobustnessKind(LiveKind):
    name = "robustness"

    def __init__(self, wire, behaviour: dict):
        super().__init__(wire, behaviour)
        self.settings = behaviour["robustness"]
        self._last: tuple | None = None

    def admit(self, case: dict, options: dict) -> str | None:
        if not options.get("robustness"):
            return "the robustness phase runs only with --robustness"
        return super().admit(case, options)

    def program(self, case: dict, edition: str, options: dict) -> ProbeProgram:
        return ProbeProgram(case["id"], case, self.phase(edition, options))

    def reply_group(self, case: dict) -> str:
        return case["probe"].get("expect") or case["id"].split("/")[1]

    def phase(self, edition: str, options: dict) -> Phase:
        """The phase every probe of a run shares: one per run (its options object) and edition."""
        if self._last is not None and self._last[0] is options and self._last[1] == edition:
            return self._last[2]
        frames, skipped = self.frames(options.get("corpus", ()), edition, bool(options.get("replay_effects")))
        phase = Phase(frames, skipped, self.settings, self.wire, self.exchanges, edition,
                      dict(options.get("params", {})), float(options.get("time_scale", 1.0)), bool(options.get("restart")),
                      self.behaviour.get("bounds", {}))
        self._last = (options, edition, phase)  # holding the options keeps the identity test sound
        return phase

    def frames(self, corpus, edition: str, replay_effects: bool) -> tuple[list[Frame], list[str]]:
        """Every frame of the byte vectors of ``edition``, in corpus order, but those too large for one datagram
        and, unless ``replay_effects``, the accepted frames of messages with effects (their destinations are the
        corpus's own: an SMS number, an Iridium or IMC system a real node would reach); and why each group was
        left out."""
        limit, never = self.settings["datagram_limit"], self.settings["never_replayed"]
        effects = self.behaviour.get("message_effects", {})
        out, too_large, barred = [], [], {}
        for case in corpus:
            expect = expectation(case.data, edition)
            if expect is None:
                continue
            for encoding, text in sorted(case.data.get("frames", {}).items()):
                data = bytes.fromhex(text)
                if len(data) > limit:
                    too_large.append(f"{case.id} ({encoding})")
                    continue
                blocked = [] if replay_effects else effects.get(case.group, [])
                if expect != "invalid" and (blocked or case.group in never):
                    why = never.get(case.group) or f"{', '.join(blocked)}; --replay-effects replays them"
                    barred.setdefault(why, []).append(case.id)
                    continue
                out.append(Frame(case.id, encoding, expect, data))
        skipped = []
        if too_large:
            skipped.append(f"{counted(len(too_large), 'frame')} over {limit} bytes (one datagram's limit): "
                           f"{', '.join(too_large[:4])}"
                           + (" ..." if len(too_large) > 4 else ""))
        for why, ids in barred.items():
            skipped.append(f"{len(ids)} accepted frames of {', '.join(sorted({i.split('/')[1] for i in ids}))} ({why})")
        return out, skipped

