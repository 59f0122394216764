"""The channel to an adapter program: the program run in a process group of its own, with a thread for each of
its pipes, its stdout read as bounded lines of strict JSON, its stderr kept as a bounded tail. The session
(``subprocess.py``) speaks the protocol over it; a socket session over a connection with the same events.
"""

from __future__ import annotations

import json
import os
import queue
import resource
import signal
import subprocess
import threading
import time

import orjson

from ..inputs import nesting_problem

STDERR_KEEP = 64 * 1024
SNIPPET = 200
EXIT_DRAIN = 1.0  # seconds to read what a program wrote before it exited, once its group is killed


def snippet(raw: bytes | str) -> str:
    text = raw.decode("utf-8", "replace") if isinstance(raw, bytes) else raw
    text = text.rstrip("\r\n")
    return text if len(text) <= SNIPPET else text[:SNIPPET] + "..."


def _reject_constant(name: str):
    raise ValueError(f"{name} is not JSON")


def parse_line(raw: bytes):
    """The JSON value of a line (strict: NaN and Infinity are not JSON; nested no deeper than the code that reads
    it follows); raises ValueError."""
    try:
        value = json.loads(raw, parse_constant=_reject_constant)
    except RecursionError:
        raise ValueError("JSON nested too deeply") from None
    problem = nesting_problem(value)
    if problem:
        raise ValueError(problem)
    return value


class StderrTail:
    """The last ``STDERR_KEEP`` bytes the program(s) wrote on stderr, fed by reader threads."""

    def __init__(self):
        self._data, self._lock = bytearray(), threading.Lock()
        self.total = 0  # bytes ever added

    def add(self, chunk: bytes) -> None:
        with self._lock:
            self._data += chunk
            del self._data[:-STDERR_KEEP]
            self.total += len(chunk)

    def text(self, since: int = 0) -> str:
        """What is kept of the bytes added after the first ``since``."""
        with self._lock:
            kept = self._data[len(self._data) - min(self.total - since, len(self._data)):]
            return kept.decode("utf-8", "replace")

    def report(self) -> str:
        """All that is kept, saying first how many earlier bytes were cut."""
        with self._lock:
            cut = self.total - len(self._data)
        marker = f"[imc-conformance: the first {cut:,} bytes of the adapter's stderr were cut]\n" if cut else ""
        return marker + self.text()


class Channel:
    """What the session talks to: request lines go out through an outbox (a writer thread drains it), events come
    in on a queue. A run of the program here; a connection in a socket session."""

    def __init__(self):
        self.events: queue.SimpleQueue = queue.SimpleQueue()
        self._outbox: queue.SimpleQueue = queue.SimpleQueue()
        self.exited_at: float | None = None  # when the end (exit, closed connection) was handled

    def send(self, request) -> None:
        """Write one request object, or a batch (a list of them), as one line."""
        self._outbox.put(request_line(request))

    def close_input(self) -> None:
        """Send nothing more: a program's stdin is closed once what was sent is written (its end of input)."""
        self._outbox.put(None)

    def next_event(self, timeout: float):
        """The next event, or None if there was none within ``timeout`` seconds."""
        try:
            return self.events.get(timeout=max(timeout, 0))
        except queue.Empty:
            return None


class Process(Channel):
    """One run of the program, in a process group of its own: pipes, a thread each for stdin, stdout and
    stderr, one that waits for its exit, and an event queue.

    Events: ``("line", bytes)``, ``("oversize", first bytes)`` (stdout is no longer read after it),
    ``("eof", b"")``, ``("exit", b"")`` (the program itself ended, whoever still holds its stdout).
    """

    def __init__(self, argv: list[str], cwd, env, max_line: int, tail: StderrTail, memory_limit: int):
        self.popen = subprocess.Popen(argv, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                      cwd=cwd, env=env, shell=False, start_new_session=True)
        if memory_limit:  # set from outside: preexec_fn is unsafe while this process runs threads
            try:
                resource.prlimit(self.popen.pid, resource.RLIMIT_DATA, (memory_limit, memory_limit))
            except (ProcessLookupError, OSError):  # already gone (it is about to be seen so), or not Linux
                pass
        super().__init__()
        self._max_line = max_line
        self.stderr_start = tail.total
        self._stderr_reader = threading.Thread(target=self._read_stderr, args=(tail,), daemon=True)
        for thread in (threading.Thread(target=self._write, daemon=True),
                       threading.Thread(target=self._read_stdout, daemon=True), self._stderr_reader,
                       threading.Thread(target=self._wait, daemon=True)):
            thread.start()

    def kill_group(self) -> None:
        """Kill the program and everything it started (its process group), whether or not it still runs."""
        try:
            os.killpg(self.popen.pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass

    def exited(self) -> None:
        """The program ended: kill what it left behind, so that its stdout reaches EOF once drained."""
        if self.exited_at is None:
            self.exited_at = time.monotonic()
            self.kill_group()

    def exit_status(self, wait: float = 0.5) -> str | None:
        """How the program ended ("exited with code 3"), or None if it still runs after ``wait`` seconds."""
        try:
            code = self.popen.wait(wait)
        except subprocess.TimeoutExpired:
            return None
        return f"exited with code {code}" if code >= 0 else f"was killed by signal {-code}"

    def stop(self, *, kill: bool = False, grace: float = 2.0) -> None:
        """Close stdin, then end the program: at once with ``kill``, else terminate, wait, kill; then kill
        whatever it started."""
        self._outbox.put(None)
        if self.popen.poll() is None:
            if kill:
                self.popen.kill()
            else:
                try:
                    self.popen.wait(min(grace, 0.5))  # closing stdin lets a well-behaved program exit
                except subprocess.TimeoutExpired:
                    self.popen.terminate()
            try:
                self.popen.wait(grace)
            except subprocess.TimeoutExpired:
                self.popen.kill()
                self.popen.wait()
        self.kill_group()
        self._stderr_reader.join(grace)  # the stderr tail is complete once its reader has seen EOF

    def _write(self) -> None:
        stdin = self.popen.stdin
        try:
            while (line := self._outbox.get()) is not None:
                stdin.write(line)
                if self._outbox.empty():
                    stdin.flush()
        except OSError:
            pass  # the program is gone; the stdout reader reports it
        finally:
            try:
                stdin.close()
            except OSError:
                pass

    def _read_stdout(self) -> None:
        read_lines(self.popen.stdout, self._max_line, self.events)

    def _wait(self) -> None:
        self.popen.wait()
        self.events.put(("exit", b""))

    def _read_stderr(self, tail: StderrTail) -> None:
        stderr = self.popen.stderr
        try:
            while chunk := stderr.read1(65536):
                tail.add(chunk)
        finally:
            stderr.close()


def request_line(request) -> bytes:
    """One request object, or a batch (a list of them), as one line of JSON."""
    try:
        return orjson.dumps(request, option=orjson.OPT_APPEND_NEWLINE)
    except orjson.JSONEncodeError:  # text orjson will not write (a lone surrogate an adapter answered): escaped
        return json.dumps(request, separators=(",", ":")).encode() + b"\n"


def read_lines(stream, limit: int, events: queue.SimpleQueue, end: tuple = ("eof",)) -> None:
    """Put each line of ``stream`` on ``events`` as ``("line", bytes)``, or ``("oversize", first bytes)`` for a
    line over ``limit`` bytes (then stop reading); at the end, an event for each kind in ``end``."""
    try:
        while line := stream.readline(limit + 1):
            if len(line) > limit and not line.endswith(b"\n"):
                events.put(("oversize", line[:SNIPPET]))
                return
            events.put(("line", line))
    except OSError:  # a connection reset: its end
        pass
    finally:
        stream.close()
    for kind in end:
        events.put((kind, b""))
