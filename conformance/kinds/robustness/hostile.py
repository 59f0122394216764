"""The robustness phase's hostile blocks: the listening probes' own requests addressed to anyone, to 0 or to
another system, from the node's own id or from a system never announced, duplicated, reusing one id, many at once
(the settings' ``hostile``)."""

from __future__ import annotations

from dataclasses import replace

from ..scenario.exchanges import exchange_for
from ..scenario.values import Scope, Unresolved, resolve_message
from .script import FLOOD_ENTITY, Frame, Probe


class Hostile:
    """The phase machine's hostile blocks (a mixin of ``PhaseMachine``)."""

    def _hostile(self) -> list[tuple[str, list[Frame]]]:
        """The hostile blocks of the settings, made of the listening probes' own requests (their effects are the
        run's to allow), each as the block's kind says: addressed to anyone, to 0 or to the session's second system;
        from the node's own id or from a system the session never announced; sent twice byte for byte; several
        times with one id; many at once with fresh ids (idempotent requests only: a node may queue the others)."""
        out = []
        for kind in self.phase.settings.get("hostile", ()):
            frames = []
            for probe in self._listening():
                spec = probe.program.case["probe"]
                if "send" in spec and not (kind.get("idempotent_only") and not self._idempotent(spec)):
                    frames += self._flood(kind, probe, spec)
            if frames:
                out.append((kind["id"], frames))
        return out

    def _flood(self, kind: dict, probe: Probe, spec: dict) -> list[Frame]:
        """One probe's request as a hostile block of ``kind`` takes it."""
        to = {"anyone": 0xFFFF, "zero": 0, "other": self.addressing.other}.get(kind.get("dst"))
        src = {"node": self._node(), "stranger": self.addressing.stranger}.get(kind.get("src"), self.addressing.system)
        speaker = replace(self.addressing, system=src, entity=FLOOD_ENTITY)
        fixed: dict = {}
        unique = (lambda name: fixed.setdefault(name, self.unique(name))) if kind.get("same_ids") else self.unique
        out = []
        for i in range(kind.get("copies", 1)):
            scope = Scope(dict(self.phase.params), unique, self.epoch, addresses=self.addressing.symbols())
            try:
                message = resolve_message(spec["send"], scope, self.wire, self.phase.edition)
                if to is not None:
                    message["header"] = {"dst": to}
                data = self.wire.compose(message, spec.get("encoding"), speaker, self.epoch + i * 0.001, "hostile",
                                         self.phase.edition).data
            except (Unresolved, ValueError):
                return []  # the probe itself cannot be sent either: its own error says why
            copies = 2 if kind.get("duplicate") else 1
            out += [Frame(f"hostile/{kind['id']}/{probe.program.case_id}", spec.get("encoding", "le"), "valid", data,
                          addressed=True)] * copies
        return out

    def _idempotent(self, spec: dict) -> bool:
        """Whether a probe's request is safe to send many times (its exchange says so)."""
        scope = Scope(dict(self.phase.params), lambda name: 0, self.epoch, addresses=self.addressing.symbols())
        try:
            message = resolve_message(spec["send"], scope, self.wire, self.phase.edition)
        except Unresolved:
            return False
        exchange = exchange_for(self.phase.exchanges, self.wire, message, self.phase.edition)
        return bool(exchange and exchange.get("idempotent"))
