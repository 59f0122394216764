"""A run's exchange written as pcapng (``run --target … --pcap FILE``): every datagram sent and received with
its time and addresses, each commented with the scenario and step that sent it (or ``received``), and the
section commented with what the run was (suite, edition, scenarios, settings) so that ``pcap`` can replay
the scenario engine over it."""

from __future__ import annotations

import json
import math
import time

from ..inputs import parse_json
from ..limits import STARTUP_MAX, TIME_SCALE_MAX, UNIQUE_SPAN
from .writing import PcapNgWriter

ABOUT = "imc-conformance run "
COMPLETE = "imc-conformance run complete"  # the last comment of a run that was not interrupted
RECEIVED, OWN = "received", "the session's own"  # the comments of what the session received, and of its manners
DAMAGED = "(damaged on purpose)"  # ends the comment of a frame a scenario sends invalid by design (its CRC flipped)


class Recorder:
    """Records a run; a recording that cannot be written (a full disk) stops, says why in ``failed``, and never
    stops the run."""

    def __init__(self, path, about: dict, prefix: str = ABOUT):
        """``prefix``: what the section comment starts with (``ABOUT``: a run ``pcap`` can replay)."""
        self.path = path
        self.handle = open(path, "wb")  # noqa: SIM115 - open for the whole run, closed by close()
        self.count = 0
        self.failed: str | None = None
        self._safely(lambda: setattr(self, "writer", PcapNgWriter(self.handle, prefix + json.dumps(about, sort_keys=True))))

    def record(self, epoch: float, src: tuple, dst: tuple, data: bytes, comment: str) -> None:
        if self.failed is None and self._safely(lambda: self.writer.write(epoch, src, dst, bytes(data), comment)):
            self.count += 1
            self.last = epoch

    def close(self, complete: bool) -> None:
        """Close the file; a run that ended, not one interrupted, says so in its last comment."""
        if complete and self.failed is None:
            self._safely(lambda: self.writer.close(getattr(self, "last", time.time()), COMPLETE))
        self._safely(self.handle.close)

    def _safely(self, write) -> bool:
        try:
            write()
            return True
        except OSError as exc:
            self.failed = self.failed or f"{exc.strerror or exc} after {self.count} datagrams"
            return False


def about_run(suite: str, edition: str, case_ids: list[str], options: dict, target: str, src, dst,
              startup: float, first_unique: int | None = None) -> dict:
    """What the section comment says of a run: enough to plan its scenarios again (``first_unique``: where its
    request ids started, when chosen for the run; a replay then finds the same ids, and the same session id)."""
    return {"suite": suite, "edition": edition, "cases": case_ids, "target": target, "src": src, "dst": dst,
            "startup": startup, **({"first_unique": first_unique} if first_unique is not None else {}), "params": options.get("params", {}), "effects": sorted(options.get("effects", ())),
            "time_scale": options.get("time_scale", 1.0), "profile": options["profile"]["name"],
            "claims": dict(sorted(options["claims"].items())) if "claims" in options else None}


def read_about(sections: list[str]) -> dict | None:
    """The run a capture's section comments describe, if it was written by ``run --pcap``; ValueError if the
    comment is there but damaged (a value of the wrong kind or out of range)."""
    for text in sections:
        if text.startswith(ABOUT) and text != COMPLETE:
            try:
                about = parse_json(text[len(ABOUT):], "the recorded run's description")
            except ValueError as exc:
                raise ValueError(f"{exc} (it is damaged)") from None
            problem = _problem(about)
            if problem:
                raise ValueError(f"the recorded run's description is damaged: {problem}")
            return about
    return None


def run_ended(sections: list[str]) -> bool:
    """Whether the recorded run ended (it was not interrupted, and the file is whole)."""
    return COMPLETE in sections


def _problem(about) -> str | None:
    """What is wrong in a run's description, or None."""
    if not isinstance(about, dict):
        return "not an object"
    kinds = {"suite": str, "edition": str, "target": str, "profile": str, "cases": list, "params": dict,
             "effects": list}
    for key, kind in kinds.items():
        if not isinstance(about.get(key), kind):
            return f"{key} is not a {kind.__name__}"
    if not all(isinstance(c, str) for c in about["cases"] + about["effects"]):
        return "cases and effects must be lists of text"
    if not all(isinstance(v, (str, int, float)) and not isinstance(v, bool) for v in about["params"].values()):
        return "params must map names to text or numbers"
    for key, top in (("src", 0xFFFF), ("dst", 0xFFFF), ("first_unique", UNIQUE_SPAN)):
        value = about.get(key)
        if value is not None and (not isinstance(value, int) or isinstance(value, bool) or not 0 <= value < top):
            return f"{key} is not a number in [0, {top})"
    for key, bound in (("startup", STARTUP_MAX), ("time_scale", TIME_SCALE_MAX)):
        value = about.get(key)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0 < value <= bound \
                or not math.isfinite(value):
            return f"{key} is not a number of seconds in (0, {bound:g}]"
    claims = about.get("claims")
    if claims is not None and not (isinstance(claims, list) and all(isinstance(c, str) for c in claims)
                                   or isinstance(claims, dict) and all(isinstance(c, str) for c in claims.values())):
        return "claims must be null, a list of services (older recordings) or capabilities mapped to text"
    return None
