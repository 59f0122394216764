"""The reference node's acoustic channel: each peer has a range, a reply takes the two-way travel time at
1500 m/s, and the modem is busy until the operation ends (AcousticSystemsQuery, AcousticOperation,
AcousticRequest)."""

from __future__ import annotations

from ....kinds.vector.floats import as_float
from .framing import PROCESSING, text_of

SOUND_SPEED = 1500.0  # m/s
TURNAROUND = 0.05  # s a peer's modem takes to answer
ACOUSTIC_ENTITY = 43
SLOW_TURNAROUND = 4.0  # s a peer's modem takes to answer under the busy-then-completes variant


class Acoustic:
    """The reference node's acoustic requests (a mixin of ``ReferenceNode``)."""

    def _on_AcousticSystemsQuery(self, t: float, message: dict) -> None:
        names = ",".join(n.upper() if self.broken == "lists-other-names" else n for n in self.peers)
        names += "," if self.broken == "list-empty-items" else ""
        self._reply(t, PROCESSING, message, "AcousticSystems", {"list": names})
        if self.broken == "two-replies":
            self._reply(t, PROCESSING + 0.1, message, "AcousticSystems", {"list": names})

    def _on_AcousticSystems(self, t: float, message: dict) -> None:
        if self.broken == "answers-unsolicited-systems":  # a reply taken for a query
            self._on_AcousticSystemsQuery(t, message)

    def _on_AcousticOperation(self, t: float, message: dict) -> None:
        if self.acoustic_dead:
            return
        f = message["fields"]
        op = self._name("AcousticOperation", "op", f["op"])
        plans = {"RANGE": ("RANGE_IP", "RANGE_RECVED", "RANGE_TIMEOUT"), "REVERSE_RANGE": ("RANGE_IP", "RANGE_RECVED", "RANGE_TIMEOUT"),
                 "MSG": ("MSG_IP", "MSG_DONE", "MSG_FAILURE"), "MSG_SHORT": ("MSG_IP", "MSG_DONE", "MSG_FAILURE"),
                 "ABORT": ("ABORT_IP", "ABORT_ACKED", "ABORT_TIMEOUT")}
        system = "imc-other-system" if self.broken == "wrong-system" else f["system"]
        tag = next(self.order)

        def state(delay: float, name: str, range_: float = 0.0) -> None:
            fields = {"op": self._v("AcousticOperation", "op", name), "system": system, "range": range_, "msg": None}
            self._reply(t, delay, message, "AcousticOperation", fields, entity=ACOUSTIC_ENTITY, tag=tag)

        if op is None and self.broken != "silent-on-unsupported":  # an operation the definitions do not have
            state(PROCESSING, "MSG_FAILURE" if self.broken == "unsupported-as-failure" else "UNSUPPORTED")
        if op not in plans:
            return  # a state (sent by another node), not a request
        if self.broken in ("dies-on-empty-msg", "restarts-on-empty-msg") and op in ("MSG", "MSG_SHORT") and f["msg"] is None:
            if self.broken == "dies-on-empty-msg":  # as DUNE's CommManager, which dereferences the missing message
                self.acoustic_dead = True
            else:  # as DUNE's CommManager, restarted
                self.cancelled.update(tag for tag, _ in self.ranging.values())
                self.ranging.clear()
                self.modem_free_at = t
            return
        distance = self.peers.get(text_of(f["system"]))
        if distance is None and self.variant == "silent-to-unknown-systems":
            return  # it cannot route the request
        if op == "RANGE" and self._repeated_range(t, text_of(f["system"])):
            return
        if t < self.modem_free_at:
            if self.variant == "queues-operations":  # carried out once the operations before it are done
                self._on_AcousticOperation(self.modem_free_at, message)
                return
            state(PROCESSING, "BUSY")
            if self.variant == "busy-then-completes":
                self._on_AcousticOperation(self.modem_free_at, message)
            return
        progress, success, failure = plans[op]
        silent = self.variant == "silent-where-allowed"
        if silent and (op in ("MSG_SHORT", "REVERSE_RANGE") or f["msg"] is None and op == "MSG"):
            return
        if op == "REVERSE_RANGE" and self.variant == "declines-reverse-range":
            state(PROCESSING, "UNSUPPORTED")
            return
        if op in ("MSG", "MSG_SHORT") and f["msg"] is None:
            state(PROCESSING, failure)  # nothing to send: the request cannot be fulfilled
            return
        if self.broken == "wrong-kind-terminal" and op == "RANGE":
            success = "MSG_DONE"
        if self.broken == "msg-ends-in-range" and op == "MSG":
            success = "RANGE_RECVED"
        if self.broken == "silent-on-abort" and op == "ABORT" and distance is not None:
            return
        travel = 2.0 if distance is None else 2 * distance / SOUND_SPEED + self.turnaround
        if distance is None and self.variant == "queues-operations":  # no answer: it gives up at its acoustic timeout
            travel = float(self.acoustic_timeout)
        self.modem_free_at = t + travel
        if op == "RANGE":
            self.ranging[text_of(f["system"])] = (tag, t + travel)
        if self.variant == "queued-first" and progress == "MSG_IP":
            state(PROCESSING / 2, "MSG_QUEUED")
        state(PROCESSING, progress)
        if distance is None:
            reached = (op == "ABORT" and self.broken == "acks-unreachable"
                       or op == "MSG" and self.variant == "msg-to-unreachable-done")
            state(travel, success if reached else failure)
        else:
            state(travel, success, float(distance) if "RANGE" in op else 0.0)

    def _repeated_range(self, t: float, system: str) -> bool:
        """A RANGE to a system a RANGE is still under way to: whether it is dealt with here. The seeds leave one
        terminal or two open (two-requests-one-system): usually the second finds the modem busy (BUSY); it may
        replace the first (repeat-range-replaces: nothing more is said of the first, the second is carried out);
        broken, the node drops both (neither ends)."""
        under_way = self.ranging.get(system)
        if under_way is None or under_way[1] <= t or (self.variant != "repeat-range-replaces"
                                                       and self.broken != "repeat-range-drops-both"):
            return False
        self.cancelled.add(under_way[0])  # the first says nothing more of itself
        self.modem_free_at = t
        del self.ranging[system]
        return self.broken == "repeat-range-drops-both"

    def _on_AcousticRequest(self, t: float, message: dict) -> None:
        if self.acoustic_dead:
            return
        f = message["fields"]
        kind = self._name("AcousticStatus", "type", f["type"])
        if self.broken == "dies-after-raw" and kind == "RAW":
            self.acoustic_dead = True
            return
        echoed_type = self._v("AcousticStatus", "type", "MSG") if self.broken == "type-not-echoed" else f["type"]
        req_id = (f["req_id"] + 1) % 0x10000 if self.broken == "req-id-not-echoed" else f["req_id"]
        tag, previous = next(self.order), self.requests.get(f["req_id"])
        if previous is not None and previous[1] > t and self._reused(t, message, previous):
            return

        def status(delay: float, name: str, range_: float = 0.0, info: str = "") -> None:
            fields = {"req_id": req_id, "type": echoed_type, "status": self._status(name), "info": info, "range": range_}
            self._reply(t, delay, message, "AcousticStatus", fields, entity=ACOUSTIC_ENTITY, tag=tag)

        distance = self.peers.get(text_of(f["destination"]))
        if distance is None and self.variant == "silent-to-unknown-systems":
            return  # it cannot route the request
        if kind == "REVERSE_RANGE" and self.variant in ("silent-where-allowed", "declines-reverse-range"):
            if self.variant == "declines-reverse-range":
                status(PROCESSING, "UNSUPPORTED", info="reverse ranges are not supported")
            return
        if t < self.modem_free_at:
            status(PROCESSING, "BUSY", info="the modem is busy")
            if self.variant == "busy-then-completes":
                self._on_AcousticRequest(self.modem_free_at, message)
            return
        if kind == "RAW" and (f["msg"] is None or f["msg"]["abbrev"] != "DevDataBinary") and self.broken != "raw-accepted":
            status(PROCESSING, "UNSUPPORTED", info="RAW expects a DevDataBinary")
            return
        if kind == "MSG" and f["msg"] is None:
            status(PROCESSING, "INPUT_FAILURE", info="no message to send")
            return
        if distance is None:
            status(PROCESSING, *(("SENT",) if self.broken == "succeeds-to-unknown" else ("INV_ADDR", 0.0, "unknown destination")))
            return
        travel = 2 * distance / SOUND_SPEED + self.turnaround
        timeout = as_float(f["timeout"])
        if self.broken == "ignores-timeout":
            travel += timeout + 2.0
        self.modem_free_at = t + travel
        final = "RANGE_RECEIVED" if "RANGE" in kind else "SENT"
        self.requests[f["req_id"]] = (tag, t + travel, message, final, float(distance) if "RANGE" in kind else 0.0)
        if self.variant == "queued-first":
            status(PROCESSING / 2, "QUEUED")
        status(PROCESSING, "IN_PROGRESS")
        if self.broken == "no-terminal":
            return
        if travel > timeout and self.broken != "ignores-timeout":  # the request's time is up before the peer's answer
            self.modem_free_at = t + timeout
            status(timeout, "INPUT_FAILURE", info="timed out")
            return
        if final == "RANGE_RECEIVED" and self.variant == "sent-before-range-received":
            status(travel / 2, "SENT")
        status(travel, final, float(distance) if final == "RANGE_RECEIVED" else 0.0)
        if self.broken == "status-after-terminal":
            status(travel + 0.1, "IN_PROGRESS")
        elif self.broken == "two-terminals":
            status(travel + 0.1, "ERROR", info="second final status")

    def _reused(self, t: float, message: dict, previous: tuple) -> bool:
        """A request reusing the req_id of an outstanding one: whether it is dealt with here (not carried out as a
        request of its own). The seeds leave it open: it may replace the first (reused-id-replaces) or cancel it
        (reused-id-cancels); broken, it crosses the two (the first's end reported with the second's type) or stops
        the node's acoustic service."""
        first_tag, end, first, final, range_ = previous
        if self.variant in ("reused-id-replaces", "reused-id-cancels") or self.broken in ("reused-id-crossed",
                                                                                         "dies-on-reused-id"):
            self.cancelled.add(first_tag)  # the first says nothing more of itself
            self.modem_free_at = t
        if self.broken == "dies-on-reused-id":
            self.acoustic_dead = True
            return True
        if self.variant == "reused-id-cancels":  # the first ends now, in a failure; the second is not carried out
            fields = {"req_id": first["fields"]["req_id"], "type": first["fields"]["type"], "status": self._status("ERROR"),
                      "info": "cancelled: a request reused its id", "range": 0.0}
            self._reply(t, PROCESSING, first, "AcousticStatus", fields, entity=ACOUSTIC_ENTITY)
            return True
        if self.broken == "reused-id-crossed":  # the first's end, reported under the second's type
            self.modem_free_at = end
            fields = {"req_id": first["fields"]["req_id"], "type": message["fields"]["type"],
                      "status": self._status(final), "info": "", "range": range_}
            self._reply(t, end - t, first, "AcousticStatus", fields, entity=ACOUSTIC_ENTITY)
            return False
        return False

    def _status(self, name: str) -> int:
        """AcousticStatus.status by name; the seeds' edition lacks UNSUPPORTED (666 fits no uint8, E1) and
        INV_ADDR: INPUT_FAILURE and ERROR stand in."""
        if name == "UNSUPPORTED" and self.variant == "old-unsupported-code":
            return 154  # 666 truncated to a byte (erratum E1)
        value = self._v("AcousticStatus", "status", name)
        if value is None or value > 0xFF:
            value = self._v("AcousticStatus", "status", {"UNSUPPORTED": "INPUT_FAILURE", "INV_ADDR": "ERROR"}[name])
        return value
