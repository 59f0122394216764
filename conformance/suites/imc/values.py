"""IMC's text and byte value forms in the decoded form (floats: ``kinds.vector.floats``).

Plaintext is a string when every byte is ASCII, else ``{"hex": ...}``; rawdata is lowercase hex.
"""

from __future__ import annotations


def text_value(raw: bytes):
    """Canonical form of plaintext bytes."""
    return raw.decode("ascii") if raw.isascii() else {"hex": raw.hex()}


def text_bytes(value) -> bytes:
    """Bytes of a plaintext value: a string stands for its UTF-8 encoding, ``{"hex"}`` for raw bytes."""
    if isinstance(value, str):
        return value.encode("utf-8")
    if isinstance(value, dict) and set(value) == {"hex"}:
        return bytes.fromhex(value["hex"])
    raise ValueError(f"{value!r} is not a plaintext value")


def raw_bytes(value) -> bytes:
    if not isinstance(value, str):
        raise ValueError(f"{value!r} is not rawdata hex")
    return bytes.fromhex(value)
