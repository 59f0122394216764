"""Library adapters over codecs that implement part of the suite, as a lab's own codec does at first.

``Adapter``: Heartbeat and LblRange only (the reference codec for them); every other message's request answered
``unsupported``, every frame that fails its framing check refused. ``RefuseAll``: refuses every frame and every
message (a codec that reads nothing)."""

from __future__ import annotations

from imc_conformance.adapter_api import Rejected, Unsupported
from imc_conformance.suites.imc import codec
from imc_conformance.suites.imc.definitions import load_definitions

DEFS = load_definitions()
IMPLEMENTED = {"Heartbeat", "LblRange"}
IDS = {DEFS[name].id for name in IMPLEMENTED}


class Adapter:
    def hello(self) -> dict:
        return {"implementation": "a codec of Heartbeat and LblRange", "suites": ["imc"], "byte_orders": ["le", "be"]}

    def encode(self, suite: str, message: dict, byte_order: str) -> bytes:
        if message["abbrev"] not in IMPLEMENTED:
            raise Unsupported(f"{message['abbrev']} is not implemented")
        try:
            return codec.encode(DEFS, message, byte_order)
        except (codec.EncodeError, codec.FrameError) as exc:
            raise Rejected(str(exc), rule=exc.rule) from exc

    def decode(self, suite: str, frame: bytes) -> dict:
        try:
            decoded = codec.decode(DEFS, frame)
        except (codec.EncodeError, codec.FrameError) as exc:
            raise Rejected(str(exc), rule=exc.rule) from exc
        if decoded["abbrev"] not in IMPLEMENTED:
            raise Unsupported(f"{decoded['abbrev']} is not implemented")
        return decoded


class RefuseAll:
    def hello(self) -> dict:
        return {"implementation": "a codec that reads nothing", "suites": ["imc"], "byte_orders": ["le", "be"]}

    def encode(self, suite: str, message: dict, byte_order: str) -> bytes:
        raise Rejected("cannot encode")

    def decode(self, suite: str, frame: bytes) -> dict:
        raise Rejected("bad frame", rule="crc")
