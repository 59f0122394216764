"""A hostile subprocess adapter: the reference codec, misbehaving in the one way its MODE names.

``python hostile_adapter.py MODE [TRIGGER]``. TRIGGER is the hex of a frame; most modes misbehave only when
asked to decode exactly that frame and answer everything else correctly. ``once-*`` modes misbehave only
the first time (a marker file in ``$HOSTILE_STATE``), so the replay after a restart succeeds. Every process
this program starts appends its pid to ``$HOSTILE_PIDS``, so tests can check that none outlives the run.
"""

from __future__ import annotations

import json
import os
import select
import sys
import time
from pathlib import Path

from imc_conformance.suites.imc import codec
from imc_conformance.suites.imc.definitions import load_definitions

DEFS = load_definitions()
MODE = sys.argv[1] if len(sys.argv) > 1 else "reference"
TRIGGER = sys.argv[2] if len(sys.argv) > 2 else None
STATE = Path(os.environ["HOSTILE_STATE"]) if "HOSTILE_STATE" in os.environ else None  # never the checkout
EVIL = "\x1b]0;pwned\x07\x1b[2J\x1b[31mred\x00NUL\rFORGED: all 3623 cases PASS\x9b31m"


def note_pid(pid: int) -> None:
    if "HOSTILE_PIDS" in os.environ:
        with open(os.environ["HOSTILE_PIDS"], "a") as out:
            out.write(f"{pid}\n")


def first_time(name: str) -> bool:
    """True the first time this is asked for ``name`` in this test's state folder ($HOSTILE_STATE)."""
    marker = STATE / f"once-{name}"
    if marker.exists():
        return False
    marker.touch()
    return True


def hello() -> dict:
    reply = {"implementation": "hostile reference codec", "suites": ["imc"], "byte_orders": ["le", "be"]}
    if MODE == "hostile-text":
        reply["implementation"] = "hostile " + EVIL
    elif MODE == "no-encodings":
        reply["byte_orders"] = []
    elif MODE == "wrong-suite":
        reply["suites"] = ["ros_acomms"]
    if MODE.startswith("batched"):
        reply["batch"] = True
    return reply


def answer(request: dict) -> dict:
    """The correct answer to one request, with its ``id``."""
    reply = {"id": request["id"], "ok": True}
    try:
        if request["op"] == "hello":
            reply.update(hello())
        elif request["op"] == "encode":
            reply["frame"] = codec.encode(DEFS, request["message"], request["byte_order"]).hex()
        elif request["op"] == "decode":
            reply["message"] = codec.decode(DEFS, bytes.fromhex(request["frame"]))
        else:
            reply = {"id": request["id"], "ok": False, "unsupported": True, "error": f"op {request['op']!r}"}
    except (codec.EncodeError, codec.FrameError) as exc:
        reply = {"id": request["id"], "ok": False, "error": str(exc), "rule": exc.rule}
    if MODE == "bad-rule" and reply.get("rule"):
        reply["rule"] = "no-such-rule"
    if MODE == "nan-word" and "message" in reply:
        reply["message"] = every_nan_as_word(reply["message"])
    return reply


def every_nan_as_word(value):
    """``value`` with every ``"nan:<bits>"`` answered as ``"nan"`` (what the old contract told adapters to do)."""
    if isinstance(value, dict):
        return {k: every_nan_as_word(v) for k, v in value.items()}
    if isinstance(value, list):
        return [every_nan_as_word(v) for v in value]
    return "nan" if isinstance(value, str) and value.startswith("nan:") else value


def misbehave(request: dict, reply: dict) -> str | None:
    """The line to write instead of ``reply`` for the trigger frame (None: the correct answer)."""
    ident = request["id"]
    if MODE == "hang":
        if STATE is not None:
            (STATE / "hanging").touch()
        time.sleep(3600)
    if MODE in ("crash", "always-crashes", "crash-leaves-child"):
        sys.stderr.write("hostile: dying on the trigger frame\n")
        sys.stderr.flush()
        os._exit(3)
    if MODE == "garbage" or (MODE == "once-garbage" and first_time("garbage")):
        return "Segmentation fault? no: just garbage on stdout"
    if MODE == "unknown-id" or (MODE == "once-wrong-id" and first_time("wrong-id")):
        return json.dumps({**reply, "id": ident + 1_000_000})
    if MODE == "huge-line" or (MODE == "once-huge" and first_time("huge")):
        return json.dumps({"id": ident, "ok": True, "message": "x" * 50_000_000})
    if MODE == "once-close-stdout" and first_time("close"):
        os.close(1)
        time.sleep(3600)
    if MODE == "liar":
        reply["message"]["fields"]["range"] += 1
    elif MODE == "malformed":
        return json.dumps({"id": ident, "ok": True})
    elif MODE == "internal":
        return json.dumps({"id": ident, "ok": False, "internal": True, "error": "KeyError: 'range'"})
    elif MODE == "hostile-internal":
        return json.dumps({"id": ident, "ok": False, "internal": True, "error": "KeyError " + EVIL})
    elif MODE == "unknown-message":
        reply["message"]["abbrev"] = "NoSuchMessage"
    elif MODE == "extra-field":
        reply["message"]["fields"]["bogus"] = 1
    elif MODE == "bad-float":
        reply["message"]["fields"]["range"] = "banana"
    elif MODE == "deep-json":  # JSON nested beyond what any reader follows
        return '{"id": %d, "ok": true, "message": %s%s}' % (ident, "[" * 100_000, "]" * 100_000)
    elif MODE == "deep-message":  # a well-formed message nested 90 inline messages deep
        inner = {"abbrev": "LblRange", "fields": dict(reply["message"]["fields"])}
        for _ in range(90):
            inner = {"abbrev": "AcousticMessage", "fields": {"message": inner}}
        reply["message"]["fields"]["range"] = inner
    elif MODE == "hostile-text":
        return json.dumps({"id": ident, "ok": False, "error": "refused " + EVIL})
    elif MODE == "partial-line":
        sys.stdout.write(json.dumps(reply)[:10])
        sys.stdout.flush()
        os._exit(0)
    elif MODE == "fork-exit":
        if os.fork() == 0:  # the child keeps stdout open and outlives its parent
            note_pid(os.getpid())
            time.sleep(600)
            os._exit(0)
        os._exit(7)
    return None


def serve_in_order() -> None:
    for line in sys.stdin:
        request = json.loads(line)
        reply = answer(request)
        is_trigger = request.get("op") == "decode" and request.get("frame") == TRIGGER
        if MODE == "always-crashes" and request["op"] != "hello":
            misbehave(request, reply)
        text = misbehave(request, reply) if is_trigger else None
        sys.stdout.write((text if text is not None else json.dumps(reply)) + "\n")
        sys.stdout.flush()


def serve_batched() -> None:
    """Batches (arrays of requests) taken as the hello offers: answered by an array in reverse order
    (``batched``), one line per request (``batched-lines``), or by an array whose answer to the trigger frame
    is malformed (``batched-bad``)."""
    for line in sys.stdin:
        request = json.loads(line)
        requests = request if isinstance(request, list) else [request]
        replies = []
        for r in requests:
            reply = answer(r)
            if MODE == "batched-bad" and r.get("op") == "decode" and r.get("frame") == TRIGGER:
                reply = {"id": r["id"], "ok": True}
            replies.append(reply)
        if MODE == "batched-lines" or not isinstance(request, list):
            sys.stdout.writelines(json.dumps(reply) + "\n" for reply in replies)
        else:
            sys.stdout.write(json.dumps(replies[::-1]) + "\n")
        sys.stdout.flush()


def serve_reversed() -> None:
    """Correct answers, each burst of requests answered in reverse order."""
    pending, buffer = [], b""
    while True:
        if not select.select([0], [], [], 0.02)[0] or len(pending) >= 16:  # input idle or a burst collected
            sys.stdout.writelines(json.dumps(answer(request)) + "\n" for request in reversed(pending))
            sys.stdout.flush()
            pending.clear()
            continue
        chunk = os.read(0, 1 << 20)
        if not chunk:
            break
        *lines, buffer = (buffer + chunk).split(b"\n")
        pending += [json.loads(line) for line in lines]


def leave_a_locked_child() -> None:
    """First start: a child holding a lock on ``$HOSTILE_STATE/held`` and sleeping; the lock frees only when it
    dies. Later starts (after the crash): wait for that lock, which is free at once if the runner killed the first
    start's process group before restarting, and never (the run hangs on the hello) if it did not."""
    import fcntl

    held = os.open(STATE / "held", os.O_RDWR | os.O_CREAT)
    if first_time("locked-child"):
        fcntl.flock(held, fcntl.LOCK_EX)
        if os.fork() == 0:  # shares the locked open file; the parent's exit leaves the lock held
            note_pid(os.getpid())
            time.sleep(600)
            os._exit(0)
    else:
        fcntl.flock(held, fcntl.LOCK_EX)


def main() -> None:
    note_pid(os.getpid())
    if MODE == "crash-leaves-child":
        leave_a_locked_child()
    if MODE == "exit-at-once":
        sys.exit("hostile: no IMC here")
    if MODE == "bad-hello":
        print("Hello, world!", flush=True)
        time.sleep(600)
    if MODE == "fork-linger" and os.fork() == 0:  # a descendant holding the pipes, left behind on purpose
        note_pid(os.getpid())
        time.sleep(600)
        os._exit(0)
    if MODE == "stderr-flood":
        sys.stderr.write("hostile stderr line\n" * 10_000)
        sys.stderr.flush()
    if MODE == "hostile-text":
        sys.stderr.write(EVIL + "\n")
    if MODE == "reversed":
        serve_reversed()
    elif MODE.startswith("batched"):
        serve_batched()
    else:
        serve_in_order()


if __name__ == "__main__":
    main()
