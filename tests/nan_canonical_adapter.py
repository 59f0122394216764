"""A library adapter, honest, over an implementation that canonicalises NaNs when it writes floats (as Java's
``Float.floatToIntBits`` does): the reference codec, every NaN written as the default quiet NaN. Its encode of a NaN
with its own bits differs from the corpus: the implementation's result, never the adapter's mistake."""

from __future__ import annotations

from imc_conformance.adapter_api import Rejected
from imc_conformance.suites.imc import codec
from imc_conformance.suites.imc.definitions import load_definitions

DEFS = load_definitions()


def canonical(value):
    """A decoded form with every NaN's own bits dropped: what the implementation writes for it."""
    if isinstance(value, dict):
        return {k: canonical(v) for k, v in value.items()}
    if isinstance(value, list):
        return [canonical(v) for v in value]
    return "nan" if isinstance(value, str) and value.startswith("nan:") else value


class Adapter:
    def hello(self) -> dict:
        return {"implementation": "a codec canonicalising NaN on encode", "suites": ["imc"],
                "byte_orders": ["le", "be"]}

    def encode(self, suite: str, message: dict, byte_order: str) -> bytes:
        try:
            return codec.encode(DEFS, canonical(message), byte_order)  # the implementation's write
        except (codec.EncodeError, codec.FrameError) as exc:
            raise Rejected(str(exc), rule=exc.rule) from exc

    def decode(self, suite: str, frame: bytes) -> dict:
        try:
            return codec.decode(DEFS, frame)
        except (codec.EncodeError, codec.FrameError) as exc:
            raise Rejected(str(exc), rule=exc.rule) from exc
