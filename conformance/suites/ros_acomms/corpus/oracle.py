"""The one-flaw oracle for the ros_acomms corpus (``kinds.vector.oracle`` over the reference codec's rule switches):
what the generator records of an invalid message's bytes, and what ``generate --check`` proves of every case."""

from __future__ import annotations

from ....kinds.vector.errors import FrameError
from ....kinds.vector.oracle import flaws as oracle_flaws, proof_problems
from .. import codec
from ..definitions import Edition, RosDefinitions


def decode_refusal(edition: Edition, full: str, frame: bytes, off: frozenset = frozenset()):
    """The rule the reference names refusing ``frame`` as ``full`` with ``off`` switched off, or None."""
    try:
        codec.decode(edition, full, frame, off=off)
    except FrameError as exc:
        return exc.rule
    return None


def flaws(edition: Edition, full: str, frame: bytes, rule: str) -> list[str]:
    """Every rule the bytes break, ``rule`` (the reference's refusal) first."""
    return oracle_flaws(lambda off: decode_refusal(edition, full, frame, off), rule)


def corpus_problems(defs: RosDefinitions, documents: list[dict]) -> tuple[list[str], dict[str, int]]:
    """The oracle over case files: every problem, by case id, and what was proven (counts)."""
    problems, counts = [], {"invalid": 0, "several flaws": 0, "practice": 0}
    for doc in documents:
        for case in doc["cases"]:
            if "rule" not in case:
                continue
            expect = case["expect"]
            edition = defs.edition(defs.editions[0] if isinstance(expect, str) else next(iter(expect)))
            rules = case.get("flaws", {}).get("rules", [case["rule"]])
            found = []
            for check in case["checks"]:
                encoding = check.split("-", 1)[1]
                if check.startswith("decode-"):
                    frame = bytes.fromhex(case["frames"][encoding])
                    found += [f"{check}: {p}" for p in proof_problems(
                        lambda off: decode_refusal(edition, case["type"], frame, off), rules)]
                else:
                    found.append(f"{check}: an invalid case of this suite is decoded, never encoded")
            problems += [f"{case['id']}: {p}" for p in found]
            if not found:
                counts["invalid"] += 1
                counts["several flaws"] += "flaws" in case
    return problems, counts
