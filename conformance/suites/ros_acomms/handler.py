"""A reference handler of seed 004's service contracts, and broken ones, as a library adapter: a dynamic queue
(GetNextQueuedMessage, UpdateQueuedMessage) and a simulated modem driver (QueueTxPacket, PingModem).

``setup`` gives it the state a scenario needs (the adapter contract documents each service's state), ``call``
answers a service request, ``publish`` takes a topic message. ``broken=NAME`` breaks one rule
(``--adapter reference-handler --adapter-arg broken=NAME``), so that the test suite can show each is caught.
"""

from __future__ import annotations

from ...adapter_api import Rejected, Unsupported
from .corpus.values import default, fields as default_fields
from .definitions import load_definitions

PACKAGE = "ros_acomms_msgs"
BREAKS = {
    "oversize": "returns messages larger than max_size_in_bits",
    "equal-size": "returns a message of exactly max_size_in_bits (the strict reading is a SHOULD: erratum S4)",
    "ignores-priority": "returns messages below minimum_priority",
    "ignores-exclude-ids": "returns messages whose ids are in exclude_message_ids",
    "ignores-require-tags": "ignores require_tags (a SHOULD)",
    "ignores-exclude-tags": "ignores exclude_tags (a SHOULD)",
    "garbage-when-empty": "has_message false, with the other fields not at their defaults (a SHOULD)",
    "claims-empty": "answers has_message false even with messages queued",
    "bits-over-data": "data_size_in_bits exceeds the bits data holds",
    "byte-rounded-size": "data_size_in_bits is the bytes' full length, not the message's (a SHOULD: erratum S5)",
    "same-message-id": "every message has the id 0, so excluding one excludes all",
    "refuses-dequeued": "refuses UpdateQueuedMessage with EVENT_LINK_DEQUEUED",
    "tail-position": "a packet inserted at the head is reported at the tail (a SHOULD)",
    "ping-never-answers": "every PingModem times out",
    "ping-negative-travel": "PingModem reports a negative one-way travel time",
    "wrong-response-type": "answers GetNextQueuedMessage with a QueueTxPacketResponse (an adapter error)",
}
EVENTS = {0, 1, 2}  # EVENT_LINK_DEQUEUED, EVENT_LINK_QUEUED, EVENT_LINK_TRANSMITTED


class ReferenceHandler:
    def __init__(self, broken: str | None = None):
        if broken is not None and broken not in BREAKS:
            raise ValueError(f"unknown broken behaviour {broken!r}; one of: {', '.join(BREAKS)}")
        self.broken = broken
        self.edition = load_definitions().edition("seed")
        self.queue: list[dict] = []
        self.events: list[tuple[int, int]] = []
        self.packets: list[dict] = []
        self.reachable: dict[int, float] = {}

    def hello(self) -> dict:
        name = "ros_acomms reference handler" + (f" (broken: {self.broken})" if self.broken else "")
        return {"implementation": name, "suites": ["ros_acomms"], "encodings": [], "kinds": ["scenario"]}

    # ------------------------------------------------------------------ the adapter contract

    def setup(self, suite: str, service: str, state: dict) -> None:
        if service == "GetNextQueuedMessage":
            self.queue = [dict(m, message_id=0 if self.broken == "same-message-id" else i + 1)
                          for i, m in enumerate(state["queue"])]
            self.events = []
        elif service == "QueueTxPacket":
            self.packets = []
        elif service == "PingModem":
            self.reachable = {int(r["dest"]): float(r["one_way_travel_time"]) for r in state["reachable"]}
        else:
            raise Unsupported(f"no handler for {service}")

    def call(self, suite: str, service: str, request: dict) -> dict:
        handler = getattr(self, "_" + service, None)
        if handler is None:
            raise Unsupported(f"no handler for {service}")
        fields = handler(request["fields"])
        name = "QueueTxPacketResponse" if self.broken == "wrong-response-type" and service == "GetNextQueuedMessage" \
            else f"{service}Response"
        full = f"{PACKAGE}/{name}"
        return {"type": full, "fields": {**default_fields(self.edition, full, default), **fields}}

    def publish(self, suite: str, type: str, message: dict) -> None:
        if type != f"{PACKAGE}/UpdateQueuedMessage":
            raise Unsupported(f"no subscriber for {type}")
        event = message["fields"]["event"]
        if event not in EVENTS or (self.broken == "refuses-dequeued" and event == 0):
            raise Rejected(f"unknown event {event}")
        self.events.append((message["fields"]["message_id"], event))

    # ------------------------------------------------------------------ the services

    def _GetNextQueuedMessage(self, r: dict) -> dict:
        for m in sorted(self.queue, key=lambda m: -m["priority"]):
            if self._eligible(m, r):
                size = m["data_size_in_bits"]
                if self.broken == "bits-over-data":
                    size = 4 * len(m["data"]) + 8
                elif self.broken == "byte-rounded-size":
                    size = 4 * len(m["data"])
                return {"has_message": self.broken != "claims-empty", "message_id": m["message_id"],
                        "dest_address": m["dest_address"], "priority": m["priority"], "data": m["data"],
                        "data_size_in_bits": size, "msg_tags": list(m["tags"])}
        if self.broken == "garbage-when-empty":
            return {"has_message": False, "message_id": 7, "data": "ff", "data_size_in_bits": 8}
        return {"has_message": False}

    def _eligible(self, m: dict, r: dict) -> bool:
        b = self.broken
        size = m["data_size_in_bits"]
        fits = (size <= r["max_size_in_bits"] if b == "equal-size" else size < r["max_size_in_bits"]) or b == "oversize"
        return (fits and (m["priority"] >= r["minimum_priority"] or b == "ignores-priority")
                and (m["message_id"] not in r["exclude_message_ids"] or b == "ignores-exclude-ids")
                and (not r["require_tags"] or set(r["require_tags"]) & set(m["tags"]) or b == "ignores-require-tags")
                and (not set(r["exclude_tags"]) & set(m["tags"]) or b == "ignores-exclude-tags"))

    def _QueueTxPacket(self, r: dict) -> dict:
        if r["insert_at_head"] and self.broken != "tail-position":
            self.packets.insert(0, r["packet"])
            position = 0
        else:
            self.packets.append(r["packet"])
            position = len(self.packets) - 1
        return {"success": True, "position_in_queue": position, "actual_src_level_db": r["requested_src_level_db"]}

    def _PingModem(self, r: dict) -> dict:
        travel = self.reachable.get(r["dest"])
        if travel is None or travel > r["timeout_sec"] or self.broken == "ping-never-answers":
            return {"timed_out": True}
        return {"timed_out": False, "one_way_travel_time": -travel if self.broken == "ping-negative-travel" else travel}
