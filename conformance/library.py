"""Drive a library adapter (an in-process Python object) through a case's requests."""

from __future__ import annotations

from typing import Iterable, Iterator

from .adapter_api import Rejected, Unsupported
from .evaluate import Answer, Request
from .session import Job


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


class LibrarySession:
    """A session over an in-process adapter object; requests run one after the other."""

    def __init__(self, adapter, name: str):
        self.adapter, self.name = adapter, name

    def hello(self) -> dict:
        return self.adapter.hello()

    def run(self, jobs: Iterable[Job]) -> Iterator[tuple[Job, Answer]]:
        for job in jobs:
            yield job, ask(self.adapter, job.suite, job.case, job.request)

    @property
    def stderr(self) -> str:
        return ""

    def close(self) -> None:
        close = getattr(self.adapter, "close", None)
        if callable(close):
            close()
