"""Drive a library adapter (an in-process Python object) through the requests of a run.

The adapter has ``hello()``, ``encode(suite, message, encoding)``, ``decode(suite, frame, **params)`` and,
for suites that describe their types, ``describe(suite, **params)``; a handler of a suite's services (whose
scenarios call it) has ``setup(suite, service, state)``, ``call(suite, service, request)`` (the response)
and ``publish(suite, type, message)``. It refuses with ``Rejected`` and declares a capability absent with
``Unsupported`` (``imc_conformance.adapter_api``). Anything else it raises is an adapter error, never a pass.
"""

from __future__ import annotations

from typing import Iterable, Iterator

from ..adapter_api import Rejected, Unsupported
from ..core.session import AdapterStartError, Answer, Job


def _call(fn, *args, acknowledge: bool = False, **kwargs) -> Answer:
    """Call the adapter; any exception other than Rejected/Unsupported is an adapter error. ``acknowledge``:
    the operation answers nothing but its success (None)."""
    try:
        result = fn(*args, **kwargs)
    except Rejected as exc:
        return Answer("rejected", reason=exc.reason, rule=exc.rule)
    except Unsupported as exc:
        return Answer("unsupported", reason=str(exc))
    except Exception as exc:  # an adapter bug must never pass a case
        return Answer("adapter-error", reason=f"{type(exc).__name__}: {exc}")
    if result.__class__ is dict:  # positional: the common answers are built at every call
        return Answer("ok", None, result)
    if result.__class__ is bytes:
        return Answer("ok", result)
    if acknowledge and result is None:
        return Answer("ok", message={})
    if isinstance(result, dict):
        return Answer("ok", message=result)
    if isinstance(result, (bytes, bytearray, memoryview)):
        return Answer("ok", frame=bytes(result))
    return Answer("adapter-error", reason=f"the adapter returned a {type(result).__name__}, not bytes or an object")


class LibrarySession:
    """A session over an in-process adapter object; requests run one after the other.

    A roundtrip reuses the implementation's answer to decoding the same frame (roundtrip is
    encode(decode(frame))), which the plan asks for just before it.
    """

    incidents: tuple = ()  # an in-process adapter cannot break the protocol

    def __init__(self, adapter, name: str):
        self.adapter, self.name = adapter, name
        self._hello: dict | None = None

    def hello(self):
        """The adapter's hello, asked once (as a subprocess is greeted once): a fuzzing run judges one example per
        run, and an adapter may read package metadata to answer."""
        if self._hello is None:
            try:
                answer = self.adapter.hello()
            except Exception as exc:  # any failure of the adapter's own hello
                raise AdapterStartError(f"the adapter's hello failed: {type(exc).__name__}: {exc}") from exc
            self._hello = answer if isinstance(answer, dict) else None
            if self._hello is None:
                return answer  # not a greeting: check_hello says what is wrong with it
        return dict(self._hello)

    def run(self, jobs: Iterable[Job]) -> Iterator[tuple[Job, Answer]]:
        decoded: dict[str, Answer] = {}  # by encoding, for the current case
        case = None
        decode, encode = getattr(self.adapter, "decode", None), getattr(self.adapter, "encode", None)  # a handler has none
        for job in jobs:
            request = job.request
            op = request.op
            if job.case_id != case:
                decoded.clear()
                case = job.case_id
            if op == "decode" or op == "roundtrip":
                key = request.encoding
                answer = decoded.pop(key, None) or _call(decode, job.suite, request.frame, **request.params)
                if op == "decode":
                    decoded[key] = answer  # kept for this frame's roundtrip check, which follows in plan order
                    yield job, answer
                else:
                    yield job, _call(encode, job.suite, answer.message, key) if answer.kind == "ok" else answer
            elif op == "encode":
                yield job, _call(encode, job.suite, request.message, request.encoding)
            elif request.op in ("setup", "call", "publish"):
                method = getattr(self.adapter, request.op, None)
                yield job, (_call(method, job.suite, acknowledge=request.op != "call", **request.params) if method
                            else Answer("unsupported", reason=f"the adapter has no {request.op} operation"))
            else:
                describe = getattr(self.adapter, "describe", None)
                yield job, (_call(describe, job.suite, **request.params) if describe is not None
                            else Answer("unsupported", reason="the adapter has no describe operation"))

    @property
    def stderr(self) -> str:
        return ""

    def close(self) -> None:
        close = getattr(self.adapter, "close", None)
        if callable(close):
            close()
