"""Drive a library adapter (an in-process Python object) through a case's requests."""

from __future__ import annotations

from .adapter_api import Rejected, Unsupported
from .evaluate import Answer, Request


def ask(adapter, suite: str, case: dict, request: Request) -> Answer:
    """Perform one request; any exception other than Rejected/Unsupported is an adapter error."""
    try:
        if request.op == "decode":
            return Answer("ok", message=adapter.decode(suite, bytes.fromhex(case["frames"][request.byte_order])))
        if request.op == "encode":
            return Answer("ok", frame=bytes(adapter.encode(suite, case["message"], request.byte_order)))
        decoded = adapter.decode(suite, bytes.fromhex(case["frames"][request.byte_order]))
        return Answer("ok", frame=bytes(adapter.encode(suite, decoded, request.byte_order)))
    except Rejected as exc:
        return Answer("rejected", reason=exc.reason, rule=exc.rule)
    except Unsupported as exc:
        return Answer("unsupported", reason=str(exc))
    except Exception as exc:  # an adapter bug must never pass a case
        return Answer("adapter-error", reason=f"{type(exc).__name__}: {exc}")
