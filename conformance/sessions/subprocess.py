"""The subprocess adapter: an implementation as a separate program speaking JSON lines.

The runner starts the program (an argv list, never a shell) and writes one JSON object per line on
its stdin; the program answers each with one line on its stdout, matched by ``id``, in any order:

* ``{"id": 1, "op": "hello"}`` -> ``{"id": 1, "ok": true, "implementation": "...", "suites": ["imc"],
  "byte_orders": ["le", "be"]}`` (the encodings the implementation emits, under the suite's name for them);
* ``{"id": 2, "op": "encode", "suite": "imc", "message": {...}, "byte_order": "le"}`` ->
  ``{"id": 2, "ok": true, "frame": "<hex>"}``;
* ``{"id": 3, "op": "decode", "suite": "imc", "frame": "<hex>"}`` (plus the suite's parameters, e.g. a ROS
  ``type``) -> ``{"id": 3, "ok": true, "message": {...}}``;
* ``{"id": 4, "op": "describe", "suite": "ros_acomms", "type": "..."}`` -> ``{"id": 4, "ok": true, ...}``
  (the type's description, for suites that check definitions);
* for handlers of a suite's services, run by its scenarios: ``{"op": "setup", "service": ..., "state": {...}}``
  and ``{"op": "publish", "type": ..., "message": {...}}`` -> ``{"ok": true}``; ``{"op": "call", "service":
  ..., "request": {...}}`` -> ``{"ok": true, "response": {...}}``.

Batched: a program whose hello answer says ``"batch": true`` is sent several requests in one line, as a
JSON array of request objects (up to ``BATCH``), and may answer with one line per request or with a line
holding an array of answers (each answer has its ``id``, as always). Either way every request gets exactly one
answer. A program without ``batch`` gets one request per line.

A refusal is ``{"id": N, "ok": false, "error": "invalid CRC", "rule": "crc"}`` (``rule`` optional).
``"unsupported": true`` declares the capability absent. ``"ok": false, "internal": true`` says the
adapter itself failed (a bug in the shim, not a refusal by the implementation): an adapter error.
Messages are in the corpus's decoded form; a roundtrip check is a decode followed by an encode of the
decoded message, two requests. Lines are strict JSON (no NaN/Infinity tokens); stderr is free text.

The program has ``hello_timeout`` (default: ``timeout``) seconds to start and answer hello. It runs in
a session (process group) of its own, so that nothing it starts outlives the run: the group is killed at
every restart and at the end. Up to ``pipeline`` requests are in flight. A request's clock starts when it
was sent or when the last answer arrived, whichever is later, so a sequential program gets ``timeout``
seconds for each request. When the program dies (seen by its PID, even if a child still holds its
stdout), stops answering, closes its stdout, writes a line that is not a JSON object with a known id, or a
line longer than ``max_line``, it is restarted (and greeted again) and the requests that were in flight
are replayed one at a time; then pipelining resumes. Such a failure is blamed (CRASH, ADAPTER_ERROR) on a
request only when it happens while that request is replayed alone, so it lands on the request that
causes it; a timeout lands on the oldest request in flight at once. A failure that names no request is
an ``Incident`` of the run, and every replayed request carries a note saying how it was answered, so that
a one-off violation is never forgiven silently. After ``MAX_RESTARTS`` restarts in a row without an
answer the remaining jobs are adapter errors.

The program's process, pipes, bounded lines and stderr tail are ``channel.py``'s; this module is the protocol.
"""

from __future__ import annotations

import json
import time
from collections import deque
from dataclasses import dataclass
from itertools import count
from typing import Iterable, Iterator

from ..core.results import Incident
from ..core.session import AdapterStartError, Answer, Job
from .channel import EXIT_DRAIN, SNIPPET, parse_line, Process, snippet, StderrTail

MAX_RESTARTS = 20
BATCH = 64  # requests per line for a program that takes batches


@dataclass
class _Call:
    """One protocol request made for a job (a roundtrip job makes two, one after the other)."""

    job: Job
    body: dict
    then_encode: bool = False  # the decode half of a roundtrip
    replayed: bool = False  # sent alone after a restart: a failure while it is in flight is its own
    sent: float = 0.0
    note: str = ""  # why it was replayed, when no request was to blame (passed on to its answer)


def _first_call(job: Job, encoding_param: str) -> _Call:
    """The first protocol request of a job."""
    request = job.request
    if request.op == "encode":
        return _Call(job, {"op": "encode", "suite": job.suite, "message": request.message, encoding_param: request.encoding})
    if request.op in ("describe", "setup", "call", "publish"):
        return _Call(job, {"op": request.op, "suite": job.suite, **request.params})
    body = {"op": "decode", "suite": job.suite, "frame": request.frame.hex(), **request.params}
    return _Call(job, body, then_encode=request.op == "roundtrip")


def _answer(op: str, reply: dict) -> Answer:
    """The Answer a well-formed reply stands for; an adapter error if the reply is malformed."""
    error, rule, ok = reply.get("error", ""), reply.get("rule"), reply.get("ok")
    if not isinstance(error, str):
        return _malformed("'error' is not a string", reply)
    if reply.get("unsupported") is True:
        return Answer("unsupported", reason=error or "unsupported")
    if ok is False and reply.get("internal") is True:
        return Answer("adapter-error", reason=f"adapter failed: {snippet(error)}")
    if ok is False:
        if rule is not None and not isinstance(rule, str):
            return _malformed("'rule' is not a string", reply)
        return Answer("rejected", reason=error, rule=rule)
    if ok is not True:
        return _malformed("no boolean 'ok'", reply)
    if op == "decode":
        message = reply.get("message")
        return Answer("ok", message=message) if isinstance(message, dict) else _malformed("no 'message' object", reply)
    if op == "describe":
        return Answer("ok", message={k: v for k, v in reply.items() if k not in ("id", "ok")})
    if op == "call":
        message = reply.get("response")
        return Answer("ok", message=message) if isinstance(message, dict) else _malformed("no 'response' object", reply)
    if op in ("setup", "publish"):
        return Answer("ok", message={})
    try:
        return Answer("ok", frame=bytes.fromhex(reply["frame"]))
    except (KeyError, TypeError, ValueError):
        return _malformed("'frame' is not hex", reply)


def _malformed(what: str, reply: dict) -> Answer:
    return Answer("adapter-error", reason=f"malformed answer ({what}): {snippet(json.dumps(reply))}")


class _Restart(Exception):
    """The program must be restarted; ``blame`` (the call to fail with ``answer``) may be None."""

    def __init__(self, why: str, blame: _Call | None = None, answer: Answer | None = None):
        super().__init__(why)
        self.why, self.blame, self.answer = why, blame, answer

    @property
    def incident_kind(self) -> str:
        return "crash" if self.answer.kind == "crash" else "protocol"


class SubprocessSession:
    """A session over a program speaking the JSON-lines protocol (see the module docstring)."""

    def __init__(self, argv: list[str], *, name: str, encoding_param: str, timeout: float = 5.0, cwd=None, env=None,
                 max_line: int = 1_000_000, pipeline: int = 256, hello_timeout: float | None = None,
                 memory_limit: int = 2 << 30, batch: bool = True):
        """``batch``: send batches to a program whose hello offers them (False: one request a line whatever it
        offers)."""
        self.argv, self.name, self.timeout, self.encoding_param = list(argv), name, timeout, encoding_param
        self.memory_limit = memory_limit  # bytes of data memory the program may use (RLIMIT_DATA); 0: no limit
        self.hello_timeout = timeout if hello_timeout is None else hello_timeout  # start-up may take longer
        self.cwd, self.env, self.max_line, self.pipeline = cwd, env, max_line, max(1, pipeline)
        self.batch = batch
        self._tail = StderrTail()
        self._ids = count(1)
        self._proc: Process | None = None
        self._info: dict | None = None
        self.incidents: list[Incident] = []

    @property
    def stderr(self) -> str:
        return self._tail.report()

    def hello(self) -> dict:
        """Start the program if needed; its hello answer (implementation, suites, byte_orders)."""
        if self._proc is None:
            self._start()
        return dict(self._info)

    def close(self) -> None:
        if self._proc is not None:
            self._proc.stop()
            self._proc = None

    # ------------------------------------------------------------ start and greet

    def _open(self):
        """A new channel to the program: a new run of it (a socket session opens a connection instead)."""
        try:
            return Process(self.argv, self.cwd, self.env, self.max_line, self._tail, self.memory_limit)
        except OSError as exc:
            raise AdapterStartError(f"cannot start adapter {self.argv}: {exc.strerror or exc}") from exc

    def open_channel(self):
        """A new channel to the program, not greeted (adapter-check speaks to it line by line); ``stop()`` it."""
        return self._open()

    def _start(self) -> None:
        proc = self._open()
        try:
            self._info = self._greet(proc)
        except AdapterStartError:
            proc.stop(kill=True)
            raise
        self._proc = proc

    def _greet(self, proc: Process) -> dict:
        ident = next(self._ids)
        proc.send({"id": ident, "op": "hello"})
        deadline = time.monotonic() + self.hello_timeout
        while True:
            event = proc.next_event(deadline - time.monotonic())
            if event is None and proc.exited_at is None:
                raise AdapterStartError(f"adapter did not answer hello within {self.hello_timeout:g} s")
            if event is not None and event[0] == "exit":
                proc.exited()
                deadline = min(deadline, proc.exited_at + EXIT_DRAIN)
                continue
            break
        kind, raw = event or ("eof", b"")
        if kind == "eof":
            status = proc.exit_status() or "closed its stdout"
            proc.stop(kill=True)
            tail = snippet(self._tail.text(proc.stderr_start)[-SNIPPET:].strip())
            raise AdapterStartError(f"adapter {status} before answering hello" + (f"; stderr: {tail}" if tail else ""))
        if kind == "oversize":
            raise AdapterStartError(f"adapter answered hello with a line over {self.max_line} bytes: {snippet(raw)}")
        try:
            reply = parse_line(raw)
        except ValueError:
            reply = None
        if not isinstance(reply, dict):
            raise AdapterStartError(f"adapter answered hello with something that is not a JSON object: {snippet(raw)}")
        if reply.get("id") != ident:
            raise AdapterStartError(f"adapter answered hello with id {str(reply.get('id'))[:40]!r}, expected {ident}")
        if reply.get("ok") is False:
            raise AdapterStartError(f"adapter refused hello: {snippet(str(reply.get('error', '')))}")
        if reply.get("ok") is not True:
            raise AdapterStartError(f"adapter answered hello without \"ok\": true: {snippet(raw)}")
        return {key: value for key, value in reply.items() if key not in ("id", "ok")}

    # ------------------------------------------------------------ running jobs

    def run(self, jobs: Iterable[Job]) -> Iterator[tuple[Job, Answer]]:
        """Perform every job, pipelined, yielding ``(job, Answer)`` as answers arrive."""
        state = _RunState(iter(jobs), self.encoding_param)
        try:
            while state.has_work():
                yield from state.drain()
                if not state.needs_program():
                    continue
                if self._proc is None:
                    self._start()
                self._send_what_fits(state)
                try:
                    yield from self._receive(state)
                except _Restart as restart:
                    yield from self._recover(state, restart)
        finally:
            if state.inflight:  # abandoned mid-run: the answers still coming would desynchronise the next run
                self.close()

    def _send_what_fits(self, state: _RunState) -> None:
        if state.replay:
            if not state.inflight:
                self._proc.send(self._sent(state, state.replay.popleft()))
            return
        batched = self.batch and self._info.get("batch") is True
        batch = []
        while len(state.inflight) < self.pipeline and (call := state.next_call()) is not None:
            batch.append(self._sent(state, call))
            if not batched or len(batch) == BATCH:
                self._proc.send(batch if batched else batch[0])
                batch = []
        if batch:
            self._proc.send(batch)

    def _sent(self, state: _RunState, call: _Call) -> dict:
        """The request object of a call, now in flight."""
        ident = next(self._ids)
        call.sent = time.monotonic()
        state.inflight[ident] = call
        return {"id": ident, **call.body}

    def _receive(self, state: _RunState) -> Iterator[tuple[Job, Answer]]:
        """Handle the next event of the program; raises _Restart when the program must be restarted."""
        proc = self._proc
        oldest = next(iter(state.inflight.values()))
        deadline = max(oldest.sent, state.last_answer) + self.timeout
        if proc.exited_at is not None:  # only what it wrote before it ended is still to come
            deadline = min(deadline, proc.exited_at + EXIT_DRAIN)
        event = proc.next_event(deadline - time.monotonic())
        if event is None and proc.exited_at is not None:
            raise self._unattributed(state, "crash", f"adapter {proc.exit_status()}")
        if event is None:
            raise _Restart(f"no answer within {self.timeout:g} s", oldest,
                           Answer("timeout", reason=f"no answer within {self.timeout:g} s"))
        kind, raw = event
        if kind == "exit":
            proc.exited()
            return
        if kind == "eof":
            status = proc.exit_status()
            if status is None:
                raise self._unattributed(state, "adapter-error", "adapter closed its stdout but kept running")
            raise self._unattributed(state, "crash", f"adapter {status}")
        if kind == "oversize":
            raise self._unattributed(state, "adapter-error",
                                     f"adapter wrote a line over {self.max_line} bytes: {snippet(raw)}")
        try:
            reply = parse_line(raw)
        except ValueError:
            raise self._unattributed(state, "adapter-error",
                                     f"adapter wrote a line that is not JSON: {snippet(raw)}") from None
        replies = reply if isinstance(reply, list) and reply and self._info.get("batch") is True else [reply]
        for reply in replies:
            ident = reply.get("id") if isinstance(reply, dict) else None
            call = state.inflight.pop(ident, None) if isinstance(ident, int) and not isinstance(ident, bool) else None
            if call is None:
                what = "not a JSON object" if not isinstance(reply, dict) else "an answer to no request in flight"
                raise self._unattributed(state, "adapter-error", f"adapter wrote {what}: {snippet(raw)}")
            state.answered()
            answer = _answer(call.body["op"], reply)
            answer.note = call.note
            yield from state.finish(call, answer)

    @staticmethod
    def _unattributed(state: _RunState, kind: str, reason: str) -> _Restart:
        """A failure naming no request: the in-flight request's if it was replayed alone, else no one's yet."""
        calls = list(state.inflight.values())
        blame = calls[0] if len(calls) == 1 and calls[0].replayed else None
        return _Restart(reason, blame, Answer(kind, reason=reason))

    def _recover(self, state: _RunState, restart: _Restart) -> Iterator[tuple[Job, Answer]]:
        """Fail the blamed call, queue the other calls in flight for replay, restart the program.

        When no call is to blame, the failure is an incident of the run and each replayed call is noted."""
        if restart.blame is not None:
            state.inflight = {i: c for i, c in state.inflight.items() if c is not restart.blame}
            yield from state.finish(restart.blame, restart.answer)
        else:
            calls = list(state.inflight.values())
            ids = list(dict.fromkeys(c.job.case_id for c in calls))
            self.incidents.append(Incident(restart.incident_kind, restart.why, ids))
            for call in calls:
                call.note = (f"answered alone after the adapter was restarted: {restart.why} "
                             f"(while {len(calls)} request{'s were' if len(calls) != 1 else ' was'} in flight)")
        for call in state.inflight.values():
            call.replayed = True
        state.replay.extendleft(reversed(list(state.inflight.values())))
        state.inflight.clear()
        self._proc.stop(kill=True)
        self._proc = None
        self._tail.add(f"\n[imc-conformance: restarting the adapter: {restart.why}]\n".encode())
        state.restarts += 1
        if state.restarts > MAX_RESTARTS:
            yield from state.abandon(f"adapter keeps crashing ({MAX_RESTARTS} restarts without an answer; "
                                     f"last: {restart.why})")
            return
        try:
            self._start()
        except AdapterStartError as exc:
            yield from state.abandon(f"adapter could not be restarted: {exc}")


class _RunState:
    """What one ``run`` has left to do: jobs not yet started, calls to replay, calls in flight.

    A roundtrip job reuses the answer to decoding the same frame when the run decodes it too (the
    plan asks for decode-<order> before roundtrip-<order>): it waits, parked, for that answer and
    then only the encode half is sent. Without such a decode, a roundtrip makes both calls itself.
    """

    def __init__(self, jobs: Iterator[Job], encoding_param: str):
        self.jobs, self.encoding_param = jobs, encoding_param
        self.ready: deque[_Call] = deque()  # second halves of roundtrips, sent before new jobs
        self.replay: deque[_Call] = deque()  # sent one at a time after a restart
        self.inflight: dict[int, _Call] = {}
        self.finished: deque[tuple[Job, Answer]] = deque()  # answered without a call of their own
        self.decoding: set[tuple[str, str]] = set()  # frames whose decode is queued or in flight
        self.decoded: dict[tuple[str, str], Answer] = {}  # decode answers a later roundtrip will use
        self.parked: dict[tuple[str, str], list[Job]] = {}  # roundtrips waiting for their decode answer
        self.last_answer = 0.0
        self.restarts = 0  # in a row, without an answer
        self._exhausted = False
        self._case: str | None = None  # the case of the last job pulled

    def needs_program(self) -> bool:
        return bool(self.inflight or self.replay or self.ready)

    def has_work(self) -> bool:
        self._pull()
        return bool(self.needs_program() or self.finished or self.parked)

    def drain(self) -> Iterator[tuple[Job, Answer]]:
        while self.finished:
            yield self.finished.popleft()

    def next_call(self) -> _Call | None:
        self._pull()
        return self.ready.popleft() if self.ready else None

    def _pull(self) -> None:
        """Make the next job's first call ready if nothing else is."""
        while not self.ready and not self._exhausted:
            job = next(self.jobs, None)
            if job is None:
                self._exhausted = True
                return
            if job.case_id != self._case:  # a case's roundtrips follow its decodes: older answers are not needed
                self.decoded.clear()
                self._case = job.case_id
            key = (job.case_id, job.request.encoding)
            if job.request.op == "roundtrip" and key in self.decoded:
                self._after_decode(job, self.decoded.pop(key))
            elif job.request.op == "roundtrip" and key in self.decoding:
                self.parked.setdefault(key, []).append(job)
            else:
                if job.request.op == "decode":
                    self.decoding.add(key)
                self.ready.append(_first_call(job, self.encoding_param))

    def _after_decode(self, job: Job, decoded: Answer) -> None:
        """Continue a roundtrip with the implementation's decoding: encode it, or fail as the decode did."""
        if decoded.kind == "ok":
            body = {"op": "encode", "suite": job.suite, "message": decoded.message,
                    self.encoding_param: job.request.encoding}
            self.ready.appendleft(_Call(job, body, note=decoded.note))
        else:
            self.finished.append((job, decoded))

    def answered(self) -> None:
        self.last_answer, self.restarts = time.monotonic(), 0

    def finish(self, call: _Call, answer: Answer) -> Iterator[tuple[Job, Answer]]:
        """Yield the job's answer (releasing roundtrips that wait for it), or continue a roundtrip's decode half."""
        if call.then_encode:
            self._after_decode(call.job, answer)
            return
        job = call.job
        key = (job.case_id, job.request.encoding)
        if job.request.op == "decode" and key in self.decoding:
            self.decoding.discard(key)
            waiting = self.parked.pop(key, None)
            if waiting:
                for parked in waiting:
                    self._after_decode(parked, answer)
            else:
                self.decoded[key] = answer
        yield job, answer

    def abandon(self, reason: str) -> Iterator[tuple[Job, Answer]]:
        """Every job not yet answered fails with ``reason``."""
        answer = Answer("adapter-error", reason=reason)
        pending = [call.job for call in (*self.replay, *self.ready)]
        pending += [job for jobs in self.parked.values() for job in jobs]
        self.replay.clear()
        self.ready.clear()
        self.parked.clear()
        yield from self.drain()
        for job in pending:
            yield job, answer
        for job in self.jobs:
            yield job, answer
        self._exhausted = True
