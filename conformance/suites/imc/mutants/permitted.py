"""Permitted choices: mutants whose difference the protocol allows; they must survive."""

from __future__ import annotations

from ....adapter_api import Rejected, Unsupported
from ..codec import FOOTER_SIZE
from .base import Reference, Stepwise


# ---------------------------------------------------------------- permitted choices: these must survive

class RefusesTrailingBytes(Stepwise):
    """Refuses a frame with bytes after the footer (imc-wire permits it: an acceptable case, not a failure)."""

    name = "refuses-trailing-bytes"
    equivalent = "imc-wire permits refusing bytes after the footer (acceptable cases): a conforming choice"

    def payload_end(self, frame, size):
        end = super().payload_end(frame, size)
        if len(frame) > end + FOOTER_SIZE:
            raise Rejected(f"{len(frame) - end - FOOTER_SIZE} bytes after the footer")
        return end


class LittleEndianOnly(Reference):
    """Emits only little-endian frames and says so (byte_orders ["le"]); it still decodes both orders."""

    name = "le-only"
    byte_orders = ("le",)
    equivalent = "an implementation may emit one byte order and say so in its hello: a conforming choice"

    def encode_frame(self, message, byte_order):
        if byte_order != "le":
            raise Unsupported(f"{byte_order!r} frames are not emitted")
        return super().encode_frame(message, byte_order)
