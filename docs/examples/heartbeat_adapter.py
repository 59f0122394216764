"""A complete subprocess adapter: an IMC codec for Heartbeat (id 150, no fields), both byte orders."""
import json
import struct
import sys

HEADER = "HHHdHBHB"  # sync, mgid, size, timestamp, src, src_ent, dst, dst_ent: 20 bytes
HEARTBEAT = 150


def crc16(data: bytes) -> int:  # CRC-16/ARC (IBM), as IMC uses
    crc = 0
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = (crc >> 1) ^ 0xA001 if crc & 1 else crc >> 1
    return crc


def decode(frame: bytes) -> dict:
    if len(frame) < 20:
        raise ValueError("header-truncated", "shorter than a header")
    order = {b"\x54\xfe": "<", b"\xfe\x54": ">"}.get(frame[:2])
    if order is None:
        raise ValueError("sync", "bad synchronization number")
    _, mgid, size, timestamp, src, src_ent, dst, dst_ent = struct.unpack(order + HEADER, frame[:20])
    if len(frame) < 20 + size + 2:
        raise ValueError("size-exceeds-data", "size larger than the data")
    (crc,) = struct.unpack(order + "H", frame[20 + size:22 + size])
    if crc != crc16(frame[:20 + size]):
        raise ValueError("crc", "CRC mismatch")
    if mgid != HEARTBEAT:
        raise LookupError(f"message id {mgid} is not implemented")
    header = {"timestamp": timestamp, "src": src, "src_ent": src_ent, "dst": dst, "dst_ent": dst_ent}
    return {"abbrev": "Heartbeat", "header": header, "fields": {}}


DEFAULT_HEADER = {"timestamp": 0.0, "src": 0xFFFF, "src_ent": 0xFF, "dst": 0xFFFF, "dst_ent": 0xFF}


def encode(message: dict, byte_order: str) -> bytes:
    h = DEFAULT_HEADER | message["header"]  # a header field the request leaves out: the codec's default
    order = "<" if byte_order == "le" else ">"
    head = struct.pack(order + HEADER, 0xFE54, HEARTBEAT, 0, h["timestamp"], h["src"], h["src_ent"], h["dst"],
                       h["dst_ent"])
    return head + struct.pack(order + "H", crc16(head))


def answer(request: dict) -> dict:
    op = request["op"]
    if op == "hello":
        return {"ok": True, "implementation": "heartbeat-example 1.0", "suites": ["imc"], "byte_orders": ["le", "be"]}
    if op == "decode":
        try:
            return {"ok": True, "message": decode(bytes.fromhex(request["frame"]))}
        except ValueError as refusal:
            rule, reason = refusal.args
            return {"ok": False, "error": reason, "rule": rule}
        except LookupError as absent:
            return {"ok": False, "unsupported": True, "error": str(absent)}
    if op == "encode" and request["message"]["abbrev"] == "Heartbeat":
        return {"ok": True, "frame": encode(request["message"], request["byte_order"]).hex()}
    return {"ok": False, "unsupported": True, "error": f"{op} of this message is not implemented"}


for line in sys.stdin:
    request = json.loads(line)
    print(json.dumps({"id": request["id"], **answer(request)}), flush=True)
