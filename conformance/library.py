"""Drive a library adapter (an in-process Python object) through a case's requests."""

from __future__ import annotations

from typing import Iterable, Iterator

from .adapter_api import Rejected, Unsupported
from .evaluate import Answer, Request
from .session import AdapterStartError, Job


def _call(fn, *args) -> Answer:
    """Call the adapter; any exception other than Rejected/Unsupported is an adapter error."""
    try:
        result = fn(*args)
    except Rejected as exc:
        return Answer("rejected", reason=exc.reason, rule=exc.rule)
    except Unsupported as exc:
        return Answer("unsupported", reason=str(exc))
    except Exception as exc:  # an adapter bug must never pass a case
        return Answer("adapter-error", reason=f"{type(exc).__name__}: {exc}")
    if isinstance(result, dict):
        return Answer("ok", message=result)
    if isinstance(result, (bytes, bytearray, memoryview)):
        return Answer("ok", frame=bytes(result))
    return Answer("adapter-error", reason=f"the adapter returned a {type(result).__name__}, not bytes or a message")


def _roundtrip(adapter, suite: str, decoded: Answer, byte_order: str) -> Answer:
    """Encode an implementation's own decoding back in the same byte order."""
    return decoded if decoded.kind != "ok" else _call(adapter.encode, suite, decoded.message, byte_order)


def ask(adapter, suite: str, case: dict, request: Request) -> Answer:
    """Perform one request on its own."""
    if request.op == "encode":
        return _call(adapter.encode, suite, case["message"], request.byte_order)
    decoded = _call(adapter.decode, suite, bytes.fromhex(case["frames"][request.byte_order]))
    return decoded if request.op == "decode" else _roundtrip(adapter, suite, decoded, request.byte_order)


class LibrarySession:
    """A session over an in-process adapter object; requests run one after the other.

    A frame is converted from hex once per case, and the roundtrip check reuses the implementation's
    answer to decoding the same frame (roundtrip is encode(decode(frame))).
    """

    incidents: tuple = ()  # an in-process adapter cannot break the protocol

    def __init__(self, adapter, name: str):
        self.adapter, self.name = adapter, name

    def hello(self):
        try:
            return self.adapter.hello()
        except Exception as exc:  # any failure of the adapter's own hello
            raise AdapterStartError(f"the adapter's hello failed: {type(exc).__name__}: {exc}") from exc

    def run(self, jobs: Iterable[Job]) -> Iterator[tuple[Job, Answer]]:
        decoded: dict[tuple[str, str], Answer] = {}
        adapter = self.adapter
        for job in jobs:
            request = job.request
            if request.op == "encode":
                yield job, _call(adapter.encode, job.suite, job.case["message"], request.byte_order)
                continue
            key = (job.case["id"], request.byte_order)
            answer = decoded.pop(key, None)
            if answer is None:
                answer = _call(adapter.decode, job.suite, bytes.fromhex(job.case["frames"][request.byte_order]))
            if request.op == "decode":
                decoded[key] = answer  # kept for this frame's roundtrip check, which follows in plan order
                yield job, answer
            else:
                yield job, _roundtrip(adapter, job.suite, answer, request.byte_order)

    @property
    def stderr(self) -> str:
        return ""

    def close(self) -> None:
        close = getattr(self.adapter, "close", None)
        if callable(close):
            close()
