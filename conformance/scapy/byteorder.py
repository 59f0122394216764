"""The byte order IMC fields are packed in: that of the frame being dissected or built (little-endian
outside a frame)."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar

from ..suites.imc.codec import ORDERS

_prefix: ContextVar[str] = ContextVar("imc_byte_order", default=ORDERS["le"])


def prefix() -> str:
    """The struct prefix of the current byte order: ``<`` or ``>``."""
    return _prefix.get()


@contextmanager
def packing(order: str) -> Iterator[None]:
    """Pack and unpack IMC fields in ``order`` (``le`` or ``be``) within the block."""
    token = _prefix.set(ORDERS[order])
    try:
        yield
    finally:
        _prefix.reset(token)
