"""The one-flaw oracle (Wycheproof's discipline, checked rather than reviewed), generic over a suite's reference.

A suite's reference codec has a switch per rule: ``refuse(off)`` is the rule it names refusing an input with the rules
``off`` switched off (each replaced by what a reader without that check does), or None when it then accepts it. An
invalid vector that claims to break ``rules`` (its ``rule`` alone, or its ``flaws``) is proven when the reference
refuses it for the first of them, accepts it with all of them off, and refuses it for each one when only that one is
left on: no rule is missing from the list, and none is there for nothing.
"""

from __future__ import annotations

from typing import Callable

Refuse = Callable[[frozenset], "str | None"]
MAX_FLAWS = 16  # more rules than any suite has: a reference that never accepts is a defect, not a case


def flaws(refuse: Refuse, rule: str) -> list[str]:
    """Every rule an input breaks, in the order the reference finds them (``rule``, its refusal, first): each rule it
    names, switched off in turn, until it accepts. ValueError if it refuses for another rule than ``rule``."""
    found: list[str] = []
    current = refuse(frozenset())
    if current != rule:
        raise ValueError(f"the reference refuses it for {current or 'nothing (it accepts it)'}, not for {rule}")
    while current is not None:
        if current in found or len(found) >= MAX_FLAWS:
            raise ValueError(f"the reference still refuses it for {current} with {', '.join(found)} switched off")
        found.append(current)
        current = refuse(frozenset(found))
    return found


def proof_problems(refuse: Refuse, rules: list[str]) -> list[str]:
    """What is wrong with the claim that an input breaks exactly ``rules`` (empty: it is proven)."""
    problems = []
    first = refuse(frozenset())
    if first != rules[0]:
        problems.append(f"the reference refuses it for {first or 'nothing (it accepts it)'}, not for {rules[0]}")
    left = refuse(frozenset(rules))
    if left is not None:
        problems.append(f"with {', '.join(rules)} switched off the reference still refuses it, for {left}")
    if len(rules) > 1:
        for rule in rules:
            alone = refuse(frozenset(rules) - {rule})
            if alone != rule:
                problems.append(f"with only {rule} left on the reference "
                                f"{'accepts it' if alone is None else f'refuses it for {alone}'}: not one of its flaws")
    return problems
