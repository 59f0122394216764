"""A run's exchange written as pcapng (``run --target … --pcap FILE``): every datagram sent and received with
its time and addresses, each commented with the scenario and step that sent it (or ``received``), and the
section commented with what the run was (suite, edition, scenarios, settings) so that ``pcap`` can replay
the scenario engine over it."""

from __future__ import annotations

import json

from .writing import PcapNgWriter

ABOUT = "imc-conformance run "


class Recorder:
    def __init__(self, path, about: dict):
        self.path = path
        self.handle = open(path, "wb")  # noqa: SIM115 - open for the whole run, closed by close()
        self.writer = PcapNgWriter(self.handle, ABOUT + json.dumps(about, sort_keys=True))
        self.count = 0

    def record(self, epoch: float, src: tuple, dst: tuple, data: bytes, comment: str) -> None:
        self.writer.write(epoch, src, dst, bytes(data), comment)
        self.count += 1

    def close(self) -> None:
        self.handle.close()


def about_run(suite: str, edition: str, case_ids: list[str], options: dict, target: str, src, dst,
              startup: float) -> dict:
    """What the section comment says of a run: enough to plan its scenarios again."""
    return {"suite": suite, "edition": edition, "cases": case_ids, "target": target, "src": src, "dst": dst,
            "startup": startup, "params": options.get("params", {}), "effects": sorted(options.get("effects", ())),
            "time_scale": options.get("time_scale", 1.0), "profile": options["profile"]["name"],
            "claims": sorted(options["claims"]) if "claims" in options else None}


def read_about(sections: list[str]) -> dict | None:
    """The run a capture's section comments describe, if it was written by ``run --pcap``; ValueError if the
    comment is there but damaged."""
    for text in sections:
        if text.startswith(ABOUT):
            try:
                about = json.loads(text[len(ABOUT):])
            except json.JSONDecodeError as exc:
                raise ValueError(f"the recorded run's description is damaged: {exc}") from None
            if not isinstance(about, dict) or not isinstance(about.get("cases"), list):
                raise ValueError("the recorded run's description is damaged: no list of cases")
            return about
    return None
