"""The reference node's Iridium and SMS requests: sent through simulated gateways that deliver at once unless a
message's data asks them to fail, slow down or vanish (the stand-in's rule: gateway.py)."""

from __future__ import annotations

from ..values import raw_bytes
from . import gateway
from .framing import PROCESSING


class GatewayRequests:
    """The reference node's gateway requests (a mixin of ``ReferenceNode``)."""

    def _on_IridiumMsgTx(self, t: float, message: dict) -> None:
        req_id, ttl = message["fields"]["req_id"], message["fields"]["ttl"]
        req_id = (req_id + 1) % 0x10000 if self.broken == "req-id-not-echoed" else req_id
        late = ttl + 4.0 if self.broken in ("transmits-after-ttl", "late-ok") else 0.0
        states = ((PROCESSING, "QUEUED", ""), (0.2 + late, "TRANSMIT", ""), (0.5 + late, "OK", ""))
        if self.variant == "slow-iridium-link":  # sent before a ttl of 2 s, its OK 1.8 s after it
            states = ((PROCESSING, "QUEUED", ""), (1.9, "TRANSMIT", ""), (3.8, "OK", ""))
        states = states[::2] if self.broken == "late-ok" else states
        states = gateway.simulated(self._gateway_mode(message), ttl, states, "TRANSMIT", "EXPIRED", "ERROR", self.broken)
        for delay, name, text in states:
            fields = {"req_id": req_id, "status": self._v("IridiumTxStatus", "status", name), "text": text}
            self._reply(t, delay, message, "IridiumTxStatus", fields)

    def _on_SmsTx(self, t: float, message: dict) -> None:
        seq = message["fields"]["seq"]
        seq = (seq + 1) % 0x100000000 if self.broken == "seq-not-echoed" else seq
        states = ((PROCESSING, "ACCEPTED", ""), (0.2, "TRANSMITTING", ""), (0.5, "COMPLETED", ""))
        mode = self._gateway_mode(message)
        states = gateway.simulated(mode, message["fields"]["timeout"], states, "TRANSMITTING", "INTERRUPTED",
                                   "REJECTED" if mode == "gone" else "INTERRUPTED", self.broken)
        for delay, name, error in states:
            self._reply(t, delay, message, "SmsState", {"seq": seq, "state": self._v("SmsState", "state", name), "error": error})

    def _gateway_mode(self, message: dict) -> str:
        """What the simulated gateway does with a message: the stand-in's rule (gateway.py), read from its data."""
        try:
            mode = gateway.plan(raw_bytes(message["fields"]["data"]))
        except ValueError:
            return "ok"
        return "ok" if self.broken == "ok-when-gateway-fails" and mode in ("fail", "gone") else mode
