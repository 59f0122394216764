"""The reference node's store for the disruption tolerant network: the samples and RemoteCommands it keeps, the
HistoricDataQuery that reads or clears them, and the RemoteCommands it executes or forwards.

The store is bounded: a reply holds at most 65,535 bytes (max_size is a uint16), no more than ``KEPT_MAX`` of the
smallest items, so the node keeps the ``KEPT_MAX`` items a reply would send first (highest priority, then earliest)
and drops the rest (trimmed when ``KEPT_SLACK`` more have come, so a flood costs little per datagram). A reply is
built in one pass: each item measured once, taken in order while the HistoricData fits max_size and a datagram.
"""

from __future__ import annotations

from .. import codec
from ....kinds.vector.floats import as_float
from .framing import PROCESSING, UNKNOWN_ENTITY

KEPT_MAX = 8192  # items kept: more than 65,535 bytes of the smallest (15 bytes: a HistoricSample holding no sample)
KEPT_SLACK = 2048  # items beyond KEPT_MAX that may come before the store is trimmed back to it
DATAGRAM = 65_507  # the largest UDP payload over IPv4
REPLY_OTHER = codec.HEADER_SIZE + 2 + 5  # bytes of a HistoricDataQuery reply besides its data: header, CRC, req_id,
# type and max_size


class History:
    """The reference node's kept data (a mixin of ``ReferenceNode``)."""

    def _on_HistoricDataQuery(self, t: float, message: dict) -> None:
        f = message["fields"]
        req_id = (f["req_id"] + 1) % 0x10000 if self.broken == "req-id-not-echoed" else f["req_id"]
        kind = self._name("HistoricDataQuery", "type", f["type"])
        self.queries.append(t)
        while self.queries and self.queries[0] < t - 1.0:
            self.queries.popleft()
        if self.broken == "exhausted-by-many" and len(self.queries) >= 80:
            self.exhausted = True  # no request is served from now on
        if self.broken == "drops-when-many" and kind == "QUERY" and (len(self.queries) > 4 or req_id in self.dropped_ids):
            self.dropped_ids.add(req_id)
            return
        if kind == "CLEAR":
            if self.broken != "clear-keeps-data":
                self.kept.clear()
            fields = {"req_id": req_id, "type": f["type"], "max_size": f["max_size"], "data": None}
        elif kind == "QUERY" or kind == "REPLY" and self.broken == "answers-replies":
            fields = {"req_id": req_id, "type": self._v("HistoricDataQuery", "type", "REPLY"), "max_size": f["max_size"],
                      "data": self._historic_data(t, f["max_size"])}
        else:
            return
        self._reply(t, PROCESSING, message, "HistoricDataQuery", fields)

    def _historic_data(self, t: float, max_size: int) -> dict | None:
        """The kept items, highest priority first, as a HistoricData of at most ``max_size`` bytes (as many
        items as fit; none when not even an empty one fits); RemoteCommands whose timeout passed are dropped."""
        if self.broken not in ("resends-expired", "keeps-expired-commands"):
            self.kept = [m for m in self.kept if m["abbrev"] != "RemoteCommand"
                         or as_float(m["fields"]["timeout"]) > self.epoch0 + t]
        items = list(self.kept)
        if self.broken == "transmits-newest-first":
            items.reverse()
        elif self.broken != "transmits-in-arrival-order":
            items.sort(key=_priority)
        data = {"abbrev": "HistoricData", "fields": {"base_lat": 0.0, "base_lon": 0.0, "base_time": 0.0, "data": []}}
        room = DATAGRAM - REPLY_OTHER if self.broken == "ignores-max-size" else min(max_size, DATAGRAM - REPLY_OTHER)
        size = self.wire.size_of("HistoricDataQuery", "data", data)
        if size > room:
            return None
        taken = data["fields"]["data"]
        for item in items:
            size += self.wire.size_of("HistoricData", "data", [item]) - 2  # an item of a message list: 2 bytes of count
            if size > room or (self.broken != "ignores-max-size" and size > max_size):
                if self.broken == "empty-when-small":
                    return None
                break
            taken.append(item)
        return data if taken or self.broken == "ignores-max-size" else None

    def _trim_kept(self) -> None:
        """Back to the ``KEPT_MAX`` items a reply sends first, once ``KEPT_SLACK`` more have come (arrival order kept)."""
        if len(self.kept) > KEPT_MAX + KEPT_SLACK:
            first = sorted(range(len(self.kept)), key=lambda i: _priority(self.kept[i]))[:KEPT_MAX]
            self.kept = [self.kept[i] for i in sorted(first)]

    def _on_HistoricData(self, t: float, message: dict) -> None:
        """Data for the disruption tolerant network: samples are kept for transmission (those of priority -127
        are only logged), RemoteCommands inside are handled as if received alone."""
        for item in message["fields"]["data"]:
            if item is None:
                continue
            if item["abbrev"] == "HistoricSample" and (item["fields"]["priority"] > -127
                                                       or self.broken == "transmits-logged-samples"):
                if self.broken == "rewrites-producer":
                    item = {**item, "fields": {**item["fields"], "sys_id": message["header"]["src"]}}
                self.kept.append(item)
            elif item["abbrev"] == "RemoteCommand":
                self._on_RemoteCommand(t, dict(message, abbrev="RemoteCommand", fields=item["fields"]))
        self._trim_kept()

    def _on_CompressedHistory(self, t: float, message: dict) -> None:
        """Not read (a reading the seeds leave open: compressed-history-input); the broken node stops serving."""
        self.exhausted = self.exhausted or self.broken == "dies-on-compressed-history"

    def _on_RemoteCommand(self, t: float, message: dict) -> None:
        f = message["fields"]
        if f["destination"] == self.system or self.broken == "executes-others-commands":
            if f["cmd"] is not None and self.broken != "ignores-remote-commands":
                self._execute(t, f)
            if f["destination"] == self.system:
                return
        if as_float(f["timeout"]) > self.epoch0 + t or self.broken == "keeps-expired-commands":
            self.kept.append({"abbrev": "RemoteCommand", "fields": f})
            self._trim_kept()
            self._forward(t)
        elif self.broken == "forwards-expired" and f["destination"] in self.contacts:
            self.kept.append({"abbrev": "RemoteCommand", "fields": f})
            self._forward(t)

    def _forward(self, t: float, periodic: bool = False) -> None:
        """Resend the kept RemoteCommands whose recipient is a contact (as DUNE does over Wi-Fi, inside
        HistoricData), when a command comes and when its recipient appears (forwards-on-period: only every
        ``FORWARD_PERIOD`` seconds, as DUNE); the others stay kept for a QUERY's reply. A command whose timeout passed
        while it was kept is not resent (forwards-expired-stored: it is, as DUNE's DataStore checks a command's
        timeout only on arrival)."""
        if self.broken == "never-forwards" or (self.variant == "forwards-on-period") != periodic:
            return
        for command in [c for c in self.kept if c["abbrev"] == "RemoteCommand" and c["fields"]["destination"] in self.contacts]:
            self.kept.remove(command)
            if as_float(command["fields"]["timeout"]) <= self.epoch0 + t and self.broken not in (
                    "forwards-expired", "keeps-expired-commands", "forwards-expired-stored"):
                continue  # expired while kept: no more attempts
            destination = command["fields"]["destination"]
            if self.broken == "forwards-as-own":
                command = {**command, "fields": {**command["fields"], "original_source": self.system}}
            data = {"base_lat": 0.0, "base_lon": 0.0, "base_time": 0.0, "data": [command]}
            frame = self._frame(t + PROCESSING, "HistoricData", data, dst=destination, ent=0)
            self._later(t, PROCESSING, self.contacts[destination], frame)

    def _execute(self, t: float, command: dict) -> None:
        """Unpack a command for this node: handle it as a request from its original source."""
        handler = getattr(self, "_on_" + command["cmd"]["abbrev"], None)
        if handler is None or command["cmd"]["abbrev"] == "RemoteCommand":
            return
        header = {"timestamp": self.epoch0 + t, "src": command["original_source"], "src_ent": UNKNOWN_ENTITY,
                  "dst": self.system, "dst_ent": UNKNOWN_ENTITY}
        handler(t, {"abbrev": command["cmd"]["abbrev"], "header": header, "fields": command["cmd"]["fields"], "executed": True})


def _priority(item: dict) -> int:
    """The sort key of a kept item: highest priority first (a RemoteCommand has none: 0)."""
    return -item["fields"].get("priority", 0)
