"""One vector record: id, expectation, clause, definition hashes, frames, message, checks, tags."""

from __future__ import annotations

from .. import codec
from ..decoded_form import used_abbrevs
from ..definitions import Definitions, MessageDef

ALL_CHECKS = ["encode-le", "encode-be", "decode-le", "decode-be", "roundtrip"]
HEADER_FIELDS = {"timestamp", "src", "src_ent", "dst", "dst_ent"}


class MessageCases:
    """Collects the cases of one message's vector file, keeping ids unique."""

    def __init__(self, defs: Definitions, mdef: MessageDef):
        self.defs, self.mdef = defs, mdef
        self.cases: list[dict] = []
        self._ids: set[str] = set()

    def add(self, path: str, *, expect, clause: str, checks: list[str], tags: list[str],
            frames: dict[str, bytes] | None = None, message: dict | None = None, **extra) -> dict:
        case_id = f"imc/{self.mdef.abbrev}/{path}"
        if case_id in self._ids:
            raise ValueError(f"duplicate case id {case_id}")
        self._ids.add(case_id)
        if message is not None and set(message.get("header", {})) != HEADER_FIELDS:
            raise ValueError(f"{case_id}: the message must give every header field (an encoder's defaults are its own)")
        uses = used_abbrevs(self.defs, message, {self.mdef.abbrev}) if message else {self.mdef.abbrev}
        record = {"id": case_id, "expect": expect, "clause": clause,
                  "definitions": {a: self.defs[a].hash for a in sorted(uses) if a in self.defs.by_abbrev},
                  "checks": checks}
        if frames is not None:
            record["frames"] = {order: frame.hex() for order, frame in frames.items()}
        if message is not None:
            record["message"] = message
        record.update({k: v for k, v in extra.items() if v is not None})
        record["tags"] = sorted(set(tags))
        self.cases.append(record)
        return record

    def extend(self, cases: list[dict]) -> None:
        """Add cases built elsewhere (promoted fuzz findings), keeping ids unique."""
        for case in cases:
            if case["id"] in self._ids:
                raise ValueError(f"duplicate case id {case['id']}")
            self._ids.add(case["id"])
            self.cases.append(case)

    def both_orders(self, message: dict) -> tuple[dict, dict[str, bytes]]:
        """The canonical (decoded) form of ``message`` and its frames in both byte orders."""
        frames = {order: codec.encode(self.defs, message, order) for order in ("le", "be")}
        canonical = codec.decode(self.defs, frames["le"])
        return canonical, frames
