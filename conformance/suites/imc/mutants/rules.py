"""One mutant per rule of rules.json (the rule switched off), and one that names the wrong rule."""

from __future__ import annotations

from .. import codec
from ....adapter_api import Rejected
from .base import Reference


# ---------------------------------------------------------------- one mutant per rule of rules.json

class RuleOff(Reference):
    """The reference codec with one rule switched off (``off``): what a reader or writer without that check does is
    the codec's own ``LENIENT`` behaviour, the one the oracle proves the corpus against."""

    off: str

    def decode_frame(self, frame: bytes) -> dict:
        return codec.decode(self.defs, frame, off=frozenset((self.off,)))

    def encode_frame(self, message: dict, byte_order: str) -> bytes:
        return codec.encode(self.defs, message, byte_order, off=frozenset((self.off,)))


def rule_off(rule: str, equivalent: str | None = None) -> type:
    """The mutant that does not check ``rule`` (named ``<rule>-unchecked``; its bug is the codec's LENIENT text)."""
    attributes = {"name": f"{rule}-unchecked", "off": rule, "__doc__": f"{rule}: {codec.LENIENT[rule]}."}
    if equivalent:
        attributes["equivalent"] = equivalent
    return type(class_name(rule), (RuleOff,), attributes)


def class_name(rule: str) -> str:
    """``crc`` -> ``CrcUnchecked``: the mutant's class name (importable from ``imc_conformance.suites.imc.mutants``)."""
    return "".join(part.capitalize() for part in rule.split("-")) + "Unchecked"


HeaderTruncatedUnchecked = rule_off(
    "header-truncated", "a frame shorter than the header has no room for its payload and CRC: padded, it still breaks "
                        "size-exceeds-data, so a reader without this check refuses every such frame (the oracle's "
                        "flaws of every header-truncated case)")
SyncUnchecked = rule_off("sync")
SizeExceedsDataUnchecked = rule_off("size-exceeds-data")
CrcUnchecked = rule_off("crc")
UnknownIdUnchecked = rule_off("unknown-id")
FieldOverrunUnchecked = rule_off("field-overrun")
LengthOverrunUnchecked = rule_off("length-overrun")
ListCountOverrunUnchecked = rule_off("list-count-overrun")
UnknownInlineIdUnchecked = rule_off("unknown-inline-id")
PayloadOverflowUnchecked = rule_off("payload-overflow")
PER_RULE = (HeaderTruncatedUnchecked, SyncUnchecked, SizeExceedsDataUnchecked, CrcUnchecked, UnknownIdUnchecked,
            FieldOverrunUnchecked, LengthOverrunUnchecked, ListCountOverrunUnchecked, UnknownInlineIdUnchecked,
            PayloadOverflowUnchecked)


# ---------------------------------------------------------------- the right refusal, the wrong rule

class BlamesCrc(Reference):
    """Wrong rule: every refusal is right, but always reported as rule "crc"."""

    name = "blames-crc"

    def encode(self, suite, message, byte_order):
        try:
            return super().encode(suite, message, byte_order)
        except Rejected as exc:
            raise Rejected(exc.reason, rule="crc") from exc

    def decode(self, suite, frame):
        try:
            return super().decode(suite, frame)
        except Rejected as exc:
            raise Rejected(exc.reason, rule="crc") from exc
