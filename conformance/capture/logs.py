"""Mission logs as a source of frames for the capture judge: what a suite's log reader yields (``Logged`` frames,
and ``Finding``s on what the log says about them, such as a bag connection's definition) and the contract such a
reader meets. A log is judged by the same code as captured datagrams (``CaptureJudge.logged``); only reading it is
the suite's (``Suite.log_reader``). Names no protocol."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar, Protocol

from .findings import CaptureRules, Finding

HEAD = 64  # bytes of a log's (decompressed) start a reader recognises its format by


@dataclass(slots=True)
class Logged:
    """One frame of a log: its place (``number``, 1-based, and ``offset``, the byte of the decompressed log it
    begins at, or in a bag the byte its chunk begins at, ``inner`` its byte within the chunk's data), its time in
    seconds since the epoch (the frame's own timestamp, or when it was recorded), its bytes, and ``channel``: for a
    format whose frames do not name their message (a bag's connection), the object that judges them
    (``channel.frame(payload) -> Frame``), else None (the suite's ``CaptureRules.frame``); ``system``: the system
    whose clock stamped it (its sender), where the format names one."""

    number: int
    time: float
    offset: int
    payload: bytes
    inner: int | None = None
    channel: object = None
    system: object = None
    cut: ClassVar[bool] = False  # a log holds whole frames (a frame cut at the end is damage the reader states)

    def place(self, source: str) -> str:
        """Where the frame is, for a report: ``[file ]byte 1,234`` (``chunk at byte 4,117, byte 230 of its data``)."""
        if self.inner is None:
            return f"{source}byte {self.offset:,}"
        return f"{source}chunk at byte {self.offset:,}, byte {self.inner:,} of its data"


class LogReader(Protocol):
    """How a suite reads its mission logs (``Suite.log_reader``)."""

    format: str  # how reports name the format
    rules: CaptureRules  # what its frames are judged by
    edition: str  # the edition the reports name
    addressed: bool  # whether its frames name the systems they are from and to (--src, --dst, --host apply)
    gaps: bool  # whether ``units`` takes ``streams.GAP`` among the pieces (a stream read on after damage)
    notes: list[str]  # what the logs read so far say as a whole (for the report)

    def recognises(self, head: bytes) -> bool:
        """Whether a log starting with ``head`` (its first HEAD decompressed bytes) is of this format."""

    def beside(self, path: Path, use: bool) -> tuple[object | None, list[str], list[str]]:
        """What the files beside the log say about its definitions: (a suite to judge it with, where ``use`` and
        the log brings its own definitions, else None; notes for the report; problems, one line each)."""

    def units(self, pieces: Iterator[bytes], damage: list[str], name: str) -> Iterator[Logged | Finding]:
        """Every frame of the log (decompressed ``pieces``), and findings on what it says of them; what cannot be
        read is appended to ``damage`` (one line each, naming the log as ``name``) and ends the reading. ``damage``
        is the stream's own list, whose lines say what the stream found; where ``gaps``, a GAP among the pieces
        follows bytes the stream's damage cut (the frame they begin is not whole: the reader drops it, adding no
        line, one line for one damage); else a line in it when the pieces end says they stopped at damage."""
