"""A realistic IMC capture for the benchmark and the tests: a vehicle (id 30, UDP 6002) and a ground station
(0x4CF0, UDP 6001) exchanging heartbeats, LBL ranges, acoustic operations and requests with their statuses,
and Iridium transmissions with theirs; every frame with its own timestamp; a share of frames damaged (a bit
flipped, the end cut, the size field changed) as a noisy link does. As the vehicle's log, the same conversation,
optionally with a third system (a peer vehicle asking for its acoustic systems) and each system on its own clock."""

from __future__ import annotations

import random
import struct

from ...capture.writing import PCAP_HEADER, ethernet_udp, pcap_record
from .codec import encode
from .crc16 import crc16
from .definitions import Definitions

VEHICLE, STATION, PEER = 30, 0x4CF0, 31
HOSTS = {VEHICLE: ("10.0.0.30", 6002), STATION: ("10.0.0.1", 6001)}


def conversation(wire, edition: str, k: int, peer: bool = False) -> list[tuple[int, int, str, dict]]:
    """The frames (sender, addressee, message, fields with enumerations by name) of the k-th second (with the peer's,
    if ``peer``)."""
    r = lambda message, path, name: wire.resolve(message, path, name, edition)  # noqa: E731
    req = k % 65536
    out = [(VEHICLE, 0xFFFF, "Heartbeat", {})]
    out += [(VEHICLE, STATION, "LblRange", {"id": b, "range": 100.0 + b + k % 97 / 8}) for b in range(4)]
    out += [(STATION, VEHICLE, "AcousticOperation", {"op": r("AcousticOperation", "op", "RANGE"), "system": "b1",
                                                     "range": 0.0, "msg": None})]
    out += [(VEHICLE, STATION, "AcousticOperation", {"op": r("AcousticOperation", "op", state), "system": "b1",
                                                     "range": 250.0 + k % 13, "msg": None})
            for state in ("RANGE_IP", "RANGE_RECVED")]
    out += [(STATION, VEHICLE, "AcousticRequest", {"req_id": req, "destination": "lauv-xplore-2", "timeout": 30.0,
                                                   "range": 0.0, "type": r("AcousticRequest", "type", "MSG"),
                                                   "msg": {"abbrev": "Heartbeat", "fields": {}}})]
    out += [(VEHICLE, STATION, "AcousticStatus", {"req_id": req, "type": r("AcousticStatus", "type", "MSG"),
                                                  "status": r("AcousticStatus", "status", status), "info": "",
                                                  "range": 0.0}) for status in ("QUEUED", "SENT")]
    if peer and k % 2 == 0:
        out += [(PEER, 0xFFFF, "Heartbeat", {}), (PEER, VEHICLE, "AcousticSystemsQuery", {}),
                (VEHICLE, PEER, "AcousticSystems", {"list": "b1,b2"})]
    if k % 4 == 0:
        out += [(STATION, VEHICLE, "IridiumMsgTx", {"req_id": req, "ttl": 600, "destination": "", "data": "cafe"})]
        out += [(VEHICLE, STATION, "IridiumTxStatus", {"req_id": req, "status": r("IridiumTxStatus", "status", s),
                                                       "text": ""}) for s in ("QUEUED", "OK")]
    return out


def write_capture(path, defs: Definitions, wire, edition: str, frames: int, damaged: float = 0.05,
                  seed: int = 1, start: float = 1.7e9) -> dict:
    """Write a pcap of about ``frames`` frames to ``path``; what it holds (frames, damaged, bytes)."""
    rng = random.Random(seed)
    cache: dict = {}
    written = broken = k = 0
    with open(path, "wb") as out:
        out.write(PCAP_HEADER)
        while written < frames:
            items = conversation(wire, edition, k)
            for i, (src, dst, message, fields) in enumerate(items):
                t = start + k + i / len(items)
                frame = _frame(defs, cache, message, fields, src, dst, t)
                if rng.random() < damaged:
                    frame, broken = _damage(rng, frame), broken + 1
                (a, sport), (b, dport) = HOSTS[src], HOSTS[dst if dst in HOSTS else STATION]
                out.write(pcap_record(t, ethernet_udp(a, sport, b, dport, frame, written)))
                written += 1
                if written == frames:
                    break
            k += 1
    return {"frames": written, "damaged": broken}


def _frame(defs: Definitions, cache: dict, message: str, fields: dict, src: int, dst: int, t: float) -> bytes:
    """The frame, from a cached encoding of the same message with only the timestamp and CRC redone."""
    key = (message, repr(sorted(fields.items())), src, dst)
    body = cache.get(key)
    if body is None:
        header = {"timestamp": 0.0, "src": src, "src_ent": 255, "dst": dst, "dst_ent": 255}
        body = cache[key] = bytearray(encode(defs, {"abbrev": message, "header": header, "fields": fields})[:-2])
        if len(cache) > 4096:
            cache.clear()
    struct.pack_into("<d", body, 6, t)
    return bytes(body) + struct.pack("<H", crc16(body))


def _damage(rng: random.Random, frame: bytes) -> bytes:
    how = rng.randrange(3)
    if how == 0:  # a bit flipped anywhere
        out = bytearray(frame)
        out[rng.randrange(len(out))] ^= 1 << rng.randrange(8)
        return bytes(out)
    if how == 1:  # the end cut
        return frame[:rng.randrange(1, len(frame))]
    out = bytearray(frame)  # the size field changed
    struct.pack_into("<H", out, 4, (len(frame) - 22 + rng.randrange(1, 40)) % 65536)
    return bytes(out)


def write_log(path, defs: Definitions, wire, edition: str, frames: int, start: float = 1.7e9,
              clocks: dict[int, float] | None = None) -> int:
    """Write the same conversation as an LSF log (frames one after another, as DUNE's Logging task writes them, in
    the order they came); the frames written. ``clocks``: the systems whose clocks are off the vehicle's, with how
    many seconds ahead each runs (behind: negative); the peer takes part if it is among them."""
    cache: dict = {}
    written = k = 0
    clocks = clocks or {}
    with open(path, "wb") as out:
        while written < frames:
            items = conversation(wire, edition, k, PEER in clocks)[:frames - written]
            for i, (src, dst, message, fields) in enumerate(items):
                t = start + k + i / len(items) + clocks.get(src, 0.0)
                out.write(_frame(defs, cache, message, fields, src, dst, t))
            written += len(items)
            k += 1
    return written


def grow_log(recorded: bytes, path, size: int) -> dict:
    """Write an LSF log of at least ``size`` bytes made of a recorded log's frames (little-endian, as DUNE writes)
    again and again, each round later by the recording's span (its timestamps moved, its CRCs redone); what it
    holds (frames, bytes)."""
    from .lsf import LsfReader
    from .suite import load

    frames = [u.payload[:-2] for u in LsfReader(load(), None).units(iter([recorded]), [], "the recording")]
    times = [struct.unpack_from("<d", f, 6)[0] for f in frames]
    span = max(times) - min(times) + 1.0
    written = rounds = 0
    with open(path, "wb") as out:
        while written < size:
            chunk = bytearray()
            for body, t in zip(frames, times):
                frame = bytearray(body)
                struct.pack_into("<d", frame, 6, t + span * rounds)
                chunk += frame + struct.pack("<H", crc16(frame))
            out.write(chunk)
            written += len(chunk)
            rounds += 1
    return {"frames": rounds * len(frames), "bytes": written}
