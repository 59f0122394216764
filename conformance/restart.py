"""``--restart-cmd``: the command that restarts a live target so that the robustness phase can bisect, run without
a shell, in a session of its own, bounded; its exit is what counts."""

from __future__ import annotations

import os
import shutil
import subprocess
import threading

from .escaping import printable
from .inputs import command_argv

RESTART_TIMEOUT = 120.0  # seconds a --restart-cmd may take
TAIL_WAIT = 1.0  # seconds to read what a failed restart command wrote, when a node it started holds its stderr


def restart_argv(text: str) -> list[str]:
    """The restart command's argv, its program found (a usage error now, not at the first bisection)."""
    argv = command_argv(text, "--restart-cmd", "give the command that restarts the target")
    program = argv[0]
    found = (os.path.isfile(program) and os.access(program, os.X_OK)) if os.sep in program else shutil.which(program)
    if not found:
        raise ValueError(f"--restart-cmd: {printable(program)} is not a program that can be run"
                         + ("" if os.sep in program else " (not found on PATH)"))
    return argv


class _Tail:
    """The last bytes a stream carries, read by a thread until it ends: a restart command may leave the node it
    started holding its stderr, which is then drained (never left to fill and block the node) for as long as the
    node lives."""

    KEEP = 4096

    def __init__(self, stream):
        self.data = b""
        self.thread = threading.Thread(target=self._drain, args=(stream,), daemon=True)
        self.thread.start()

    def _drain(self, stream) -> None:
        with stream:
            for chunk in iter(lambda: stream.read1(65536), b""):
                self.data = (self.data + chunk)[-self.KEEP:]


def restarter(argv: list[str]):
    """A function that runs the restart command (no shell, in a session of its own, bounded) and says why it
    failed, or None. The command's exit is what counts: a node it starts in the background may hold its output."""
    def restart() -> str | None:
        try:
            proc = subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                                    start_new_session=True)
        except OSError as exc:
            return f"the restart command could not run: {exc.strerror or exc}"
        tail = _Tail(proc.stderr)
        try:
            code = proc.wait(timeout=RESTART_TIMEOUT)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
            return f"the restart command did not end within {RESTART_TIMEOUT:g} s"
        if code != 0:
            tail.thread.join(TAIL_WAIT)  # at once when nothing it started holds its stderr
            text = tail.data[-300:].decode("utf-8", "replace").strip()
            return f"the restart command exited with {code}" + (f": {printable(text)}" if text else "")
        return None
    return restart
