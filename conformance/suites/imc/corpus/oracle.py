"""The one-flaw oracle for the IMC corpus (``kinds.vector.oracle`` over the reference codec's rule switches).

``flaws`` is what the generator records of an invalid frame; ``case_problems`` is what ``generate --check`` proves of
every case on disk: an invalid frame breaks exactly the rules it names, an invalid message is refused for its rule
and encoded once that rule is off, and a case about a rule of practice is refused for it only where it is held.
"""

from __future__ import annotations

from ....kinds.vector.errors import EncodeError, FrameError, NotJudged
from ....kinds.vector.oracle import flaws as oracle_flaws, proof_problems
from .. import codec
from ..definitions import Definitions


def decode_refusal(defs: Definitions, frame: bytes, off: frozenset = frozenset(), held: frozenset = frozenset()):
    """The rule the reference names refusing ``frame`` with ``off`` switched off and ``held`` held, or None."""
    try:
        codec.decode(defs, frame, off=off, held=held)
    except FrameError as exc:
        return exc.rule
    except NotJudged as exc:
        return f"not judged ({exc.reason})"
    return None


def encode_refusal(defs: Definitions, message: dict, order: str, off: frozenset = frozenset(),
                   held: frozenset = frozenset()):
    """The rule the reference names refusing to encode ``message``, or None."""
    try:
        codec.encode(defs, message, order, off=off, held=held)
    except EncodeError as exc:
        return exc.rule
    return None


def practice_also_broken(refuse, rules: list[str], practices) -> str | None:
    """The rule of practice an invalid input also breaks (a receiver holding it may name it), if any: the one the
    reference names with the input's own rules switched off and that practice held (``refuse(off, held)``)."""
    return next((p for p in sorted(practices) if refuse(frozenset(rules), frozenset((p,))) == p), None)


def flaws(defs: Definitions, frame: bytes, rule: str) -> list[str]:
    """Every rule the frame breaks, ``rule`` (the reference's refusal) first."""
    return oracle_flaws(lambda off: decode_refusal(defs, frame, off), rule)


def case_problems(defs: Definitions, case: dict) -> list[str]:
    """What the oracle finds wrong with one case (empty: proven, or nothing to prove)."""
    out = []
    frames = {order: bytes.fromhex(h) for order, h in case.get("frames", {}).items()}
    decodes = [c.split("-", 1)[1] for c in case["checks"] if c.startswith("decode-")]
    encodes = [c.split("-", 1)[1] for c in case["checks"] if c.startswith("encode-")]
    if "rule" in case:
        rules = case.get("flaws", {}).get("rules", [case["rule"]])
        for order in decodes:
            out += [f"decode-{order}: {p}" for p in
                    proof_problems(lambda off, f=frames[order]: decode_refusal(defs, f, off), rules)]
        for order in encodes:
            out += [f"encode-{order}: {p}" for p in
                    proof_problems(lambda off, o=order: encode_refusal(defs, case["message"], o, off), rules)]
    if "practice" in case and "rule" in case:  # an invalid input that also breaks a practice a receiver may hold
        rules, held = case.get("flaws", {}).get("rules", [case["rule"]]), frozenset([case["practice"]])
        named = (decode_refusal(defs, frames[decodes[0]], frozenset(rules), held) if decodes else
                 encode_refusal(defs, case["message"], encodes[0], frozenset(rules), held))
        if named != case["practice"]:
            out.append(f"holding {case['practice']} with its own rules off, the reference names {named}, not it")
    elif "practice" in case:
        held = frozenset([case["practice"]])
        for order in decodes:
            out += practice_problems(case["practice"], f"decode-{order}", decode_refusal(defs, frames[order]),
                                     decode_refusal(defs, frames[order], held=held))
        for order in encodes:
            out += practice_problems(case["practice"], f"encode-{order}", encode_refusal(defs, case["message"], order),
                                     encode_refusal(defs, case["message"], order, held=held))
    return out


def practice_problems(rule: str, check: str, free, held) -> list[str]:
    """A case about a rule of practice is accepted by the reference, and refused for that rule where it is held."""
    out = []
    if free is not None:
        out.append(f"{check}: the reference refuses it for {free} though {rule} is a rule of practice, not held")
    if held != rule:
        out.append(f"{check}: holding {rule}, the reference {'accepts it' if held is None else f'refuses it for {held}'}")
    return out


def corpus_problems(defs: Definitions, documents: list[dict]) -> tuple[list[str], dict[str, int]]:
    """The oracle over case files (``documents``): every problem, by case id, and what was proven (counts)."""
    problems, counts = [], {"invalid": 0, "several flaws": 0, "practice": 0}
    for doc in documents:
        for case in doc["cases"]:
            found = case_problems(defs, case)
            problems += [f"{case['id']}: {p}" for p in found]
            if not found:
                counts["invalid"] += "rule" in case
                counts["several flaws"] += "flaws" in case
                counts["practice"] += "practice" in case
    return problems, counts
