"""The contract line by line, over a channel to a subprocess or socket adapter (not through the session, which would
restart the program and replay, hiding the mistake): the hello, an unknown operation, requests in flight together,
a batch. Each answer is read as the session reads it (bounded lines, strict JSON) and what is wrong is a Mistake."""

from __future__ import annotations

import json
import time

from ..core.hello import check_hello
from ..core.session import AdapterStartError
from ..sessions.channel import EXIT_DRAIN, parse_line, snippet
from .mistakes import Mistake

HELLO_ID, UNKNOWN_OP_ID = 1, 2
UNKNOWN_OP = "adapter-check-unknown-op"
MISTAKES_READ = 100  # mistaken lines read in one wait before the check stops reading (a program flooding its output)
EOF_WAIT = 3.0  # seconds a program has to exit once its input ended (the contract: answer what is in flight, exit 0)


class Line:
    """A channel and what was read from it: ``collect`` waits for the answers to some ids."""

    def __init__(self, channel, timeout: float):
        self.channel, self.timeout = channel, timeout
        self.ended = False  # nothing more is read: the program ended (or closed its output), or the check stopped
        self.closed = False  # the check closed the program's input (its end of input, as at the end of a run)
        self.stopped = False  # the check stopped reading (a line over the bound, a flood of mistakes), not the program

    def collect(self, wanted: set[int], where: str, *, arrays: bool, timeout: float | None = None):
        """The answers to ``wanted`` ids that came (each its reply object), and the mistakes in what came; waits
        ``timeout`` (default: the channel's) from the last answer."""
        answers: dict[int, dict] = {}
        mistakes: list[Mistake] = []
        wait = self.timeout if timeout is None else timeout
        deadline = time.monotonic() + wait
        while not self.ended and set(wanted) - set(answers):
            if len(mistakes) >= MISTAKES_READ:  # a flood: what was read shows the mistake; reading on would not end
                self.ended = self.stopped = True
                break
            event = self.channel.next_event(deadline - time.monotonic())
            if event is None:
                break
            kind, raw = event
            if kind == "exit":
                self.channel.exited()
                deadline = min(deadline, time.monotonic() + EXIT_DRAIN)
                continue
            if kind == "eof":
                self.ended = True
                break
            if kind == "oversize":
                mistakes.append(Mistake("long-line", snippet(raw), where))
                self.ended = self.stopped = True
                break
            try:
                value = parse_line(raw)
            except ValueError:
                mistakes.append(Mistake("nan-token" if _with_constants(raw) else "not-json", snippet(raw), where))
                continue
            if isinstance(value, list) and not arrays:
                mistakes.append(Mistake("array-unasked", snippet(raw), where))
            for item in value if isinstance(value, list) else [value]:
                ident = item.get("id") if isinstance(item, dict) else None
                if not isinstance(item, dict):
                    mistakes.append(Mistake("not-object", snippet(json.dumps(item)), where))
                elif not isinstance(ident, int) or isinstance(ident, bool) or ident not in wanted:
                    mistakes.append(Mistake("wrong-id", snippet(raw), where))
                elif ident in answers:
                    mistakes.append(Mistake("duplicate", snippet(raw), where))
                else:
                    answers[ident] = item
                    deadline = time.monotonic() + wait
        return answers, mistakes


def _with_constants(raw: bytes) -> bool:
    """Whether a line is JSON once NaN and Infinity are taken as numbers (what many writers emit)."""
    try:
        json.loads(raw)
    except (ValueError, RecursionError):
        return False
    return True


def hello(line: Line, suite: str, encodings_key: str, encodings: tuple[str, ...], stderr,
          wait: float) -> tuple[dict | None, list]:
    """The adapter's hello answer (None if it gave none the suite can use) and the mistakes in it. ``stderr()``: what
    the program wrote on stderr so far; ``wait``: seconds it has to start and answer (a JVM takes a while)."""
    where = "hello"
    line.channel.send({"id": HELLO_ID, "op": "hello"})
    answers, mistakes = line.collect({HELLO_ID}, where, arrays=False, timeout=wait)
    if HELLO_ID not in answers:
        if not line.ended and hasattr(line.channel, "popen"):  # a program: is its answer stuck in a buffer?
            line.channel.close_input()
            line.closed = True
            late, _ = line.collect({HELLO_ID}, where, arrays=False)
            if late:
                return None, mistakes + [Mistake("unflushed", snippet(json.dumps(late[HELLO_ID])), where)]
        if line.stopped:  # the check stopped reading (the long line is the mistake), not the program
            return None, mistakes
        if line.closed:  # the check ended its input: ending then is what the contract asks
            then = "; it then exited, as it should at the end of input" if line.ended else ""
            return None, mistakes + [Mistake("hello-late", f"no answer within {wait:g} s, nor once adapter-check "
                                                           f"closed its input{then}", where)]
        if line.ended:
            status = getattr(line.channel, "exit_status", lambda wait=0.5: None)() or "closed its output"
            tail = snippet(stderr()[-200:].strip())
            return None, mistakes + [Mistake("exited", f"it {status}" + (f"; stderr: {tail}" if tail else ""), where)]
        return None, mistakes + [Mistake("hello-late", f"no answer within {wait:g} s", where)]
    reply = answers[HELLO_ID]
    if reply.get("ok") is False:
        return None, mistakes + [Mistake("hello-refused", snippet(str(reply.get("error", ""))), where)]
    info = {k: v for k, v in reply.items() if k not in ("id", "ok")}
    try:
        if reply.get("ok") is not True:
            raise AdapterStartError("the adapter's hello needs \"ok\": true")
        check_hello(info, suite, encodings_key, encodings)
    except AdapterStartError as exc:
        return None, mistakes + [Mistake("hello-fields", f"{exc}; it answered {snippet(json.dumps(reply))}", where)]
    if "batch" in info and not isinstance(info["batch"], bool):
        mistakes.append(Mistake("hello-batch", snippet(json.dumps(info["batch"])), where))
    return info, mistakes


def unknown_op(line: Line, suite: str) -> list[Mistake]:
    """An operation no version of the contract has must be answered unsupported."""
    where = f"{{\"op\": \"{UNKNOWN_OP}\"}}"
    line.channel.send({"id": UNKNOWN_OP_ID, "op": UNKNOWN_OP, "suite": suite})
    answers, mistakes = line.collect({UNKNOWN_OP_ID}, where, arrays=False)
    reply = answers.get(UNKNOWN_OP_ID)
    if reply is None and line.stopped:  # the check stopped reading at a long line: that is the mistake
        return mistakes
    if reply is None:
        return mistakes + [Mistake("unknown-op", "no answer" if line.ended else f"no answer within {line.timeout:g} s",
                                   where)]
    if reply.get("ok") is not False or reply.get("unsupported") is not True:
        mistakes.append(Mistake("unknown-op", f"it answered {snippet(json.dumps(reply))}", where))
    return mistakes


def together(line: Line, requests: dict[int, dict], same, *, batch: bool) -> tuple[list[Mistake], list[int]]:
    """Send ``requests`` (id -> request) without waiting, one line each or as one batch line; every one must be
    answered, each with its own id. ``same(ident, reply)``: the id of the request whose expected answer ``reply``
    is, when that can be told (a decoded message), else None. Returns the mistakes and the ids left unanswered."""
    where = ("a batch of " if batch else "") + f"{len(requests)} requests in flight ({', '.join(map(str, requests))})"
    if batch:
        line.channel.send([{"id": i, **r} for i, r in requests.items()])
    else:
        for ident, request in requests.items():
            line.channel.send({"id": ident, **request})
    answers, mistakes = line.collect(set(requests), where, arrays=batch)
    unanswered = [i for i in requests if i not in answers]
    if unanswered:
        missing = ", ".join(map(str, unanswered))
        mistakes.append(Mistake("batch-unread" if batch else "pipelining",
                                f"answered {len(answers)} of {len(requests)}; no answer to {missing}", where))
    for ident, reply in answers.items():
        matches = same(ident, reply)
        if matches is not None and matches != ident:
            mistakes.append(Mistake("ordering", f"the answer with id {ident} is the answer to request {matches}: "
                                                f"{snippet(json.dumps(reply))}", where))
    return mistakes, unanswered


def end_of_input(line: Line) -> list[Mistake]:
    """A program must exit once its input ends (the suite ends every run so): close it and wait ``EOF_WAIT``."""
    if line.ended or not hasattr(line.channel, "popen"):
        return []
    line.channel.close_input()
    line.closed = True
    if line.channel.exit_status(wait=EOF_WAIT) is not None:
        return []
    return [Mistake("no-exit", f"it still ran {EOF_WAIT:g} s after its input ended", "end of input")]
