"""A subprocess adapter over a message with float fields: an IMC codec for LblRange (id 200: id, a u8, and range, an
fp32), both byte orders. Floats are where adapters go wrong: JSON has no NaN or infinity, so they travel as strings."""
import json
import math
import struct
import sys

HEADER = "HHHdHBHB"  # sync, mgid, size, timestamp, src, src_ent, dst, dst_ent: 20 bytes
LBLRANGE = 200
DEFAULT_HEADER = {"timestamp": 0.0, "src": 0xFFFF, "src_ent": 0xFF, "dst": 0xFFFF, "dst_ent": 0xFF}


def crc16(data: bytes) -> int:  # CRC-16/ARC (IBM), as IMC uses
    crc = 0
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = (crc >> 1) ^ 0xA001 if crc & 1 else crc >> 1
    return crc


def fp32_to_json(raw: bytes):
    """An fp32's 4 bytes (big-endian) as the decoded form writes it: the shortest decimal that reads back to the same
    fp32, "inf" or "-inf", "nan" for the default quiet NaN and "nan:<8 hex digits>" for any other."""
    (bits,) = struct.unpack(">I", raw)
    (value,) = struct.unpack(">f", raw)
    if math.isnan(value):
        return "nan" if bits == 0x7FC00000 else f"nan:{bits:08x}"
    if math.isinf(value):
        return "inf" if value > 0 else "-inf"
    for digits in range(1, 10):  # the shortest of these that reads back to the same fp32
        text = f"{value:.{digits}g}"
        try:
            if struct.pack(">f", float(text)) == raw:
                return float(text)
        except OverflowError:  # rounded beyond the largest fp32
            continue
    return value


def fp32_from_json(value) -> bytes:
    """The 4 bytes (big-endian) of an fp32 given in the decoded form."""
    if isinstance(value, str) and value.startswith("nan:"):
        return struct.pack(">I", int(value[4:], 16))
    if value == "nan":
        return struct.pack(">I", 0x7FC00000)
    return struct.pack(">f", float(value))  # "inf" and "-inf" read as floats too


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
    if mgid != LBLRANGE:
        raise LookupError(f"message id {mgid} is not implemented")
    if size < 5:
        raise ValueError("field-overrun", "the payload ends before range")
    payload = frame[20:20 + size]
    wire_range = payload[1:5] if order == ">" else payload[1:5][::-1]  # the fp32's bytes, big-endian
    header = {"timestamp": timestamp, "src": src, "src_ent": src_ent, "dst": dst, "dst_ent": dst_ent}
    return {"abbrev": "LblRange", "header": header, "fields": {"id": payload[0], "range": fp32_to_json(wire_range)}}


def encode(message: dict, byte_order: str) -> bytes:
    h = DEFAULT_HEADER | message["header"]  # a header field the request leaves out: the codec's default
    order = "<" if byte_order == "le" else ">"
    range_bytes = fp32_from_json(message["fields"]["range"])
    payload = bytes([message["fields"]["id"]]) + (range_bytes if order == ">" else range_bytes[::-1])
    head = struct.pack(order + HEADER, 0xFE54, LBLRANGE, len(payload), h["timestamp"], h["src"], h["src_ent"],
                       h["dst"], h["dst_ent"])
    return head + payload + struct.pack(order + "H", crc16(head + payload))


def answer(request: dict) -> dict:
    op = request["op"]
    if op == "hello":
        return {"ok": True, "implementation": "lblrange-example 1.0", "suites": ["imc"], "byte_orders": ["le", "be"]}
    if op == "decode":
        try:
            return {"ok": True, "message": decode(bytes.fromhex(request["frame"]))}
        except ValueError as refusal:
            rule, reason = refusal.args
            return {"ok": False, "error": reason, "rule": rule}
        except LookupError as absent:
            return {"ok": False, "unsupported": True, "error": str(absent)}
    if op == "encode" and request["message"]["abbrev"] == "LblRange":
        try:
            return {"ok": True, "frame": encode(request["message"], request["byte_order"]).hex()}
        except (struct.error, ValueError, OverflowError) as refusal:
            return {"ok": False, "error": str(refusal)}
    return {"ok": False, "unsupported": True, "error": f"{op} of this message is not implemented"}


for line in sys.stdin:
    request = json.loads(line)
    # allow_nan=False: a float NaN or infinity left in an answer raises here instead of writing NaN, which is not JSON
    print(json.dumps({"id": request["id"], **answer(request)}, allow_nan=False), flush=True)
