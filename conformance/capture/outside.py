"""Frames of messages outside the suite (a vehicle's other traffic: its navigation, its entities' states, ids of a
newer protocol): sound frames, their framing checked, judged no further and counted by message for a note, never a
failure. Live runs, ``watch``, captures and logs count them alike."""

from __future__ import annotations

from collections import Counter

from ..core.wording import counted

LISTED = 8  # messages named in a note


class Outside:
    def __init__(self):
        self.known: Counter = Counter()  # messages the protocol defines that the suite does not cover, by name
        self.undefined: Counter = Counter()  # ids no definition the suite has names, by id

    def add(self, name: str, undefined: bool = False) -> None:
        (self.undefined if undefined else self.known)[name] += 1

    def __bool__(self) -> bool:
        return bool(self.known or self.undefined)

    def notes(self, judged: str) -> list[str]:
        """The notes of a report: what was counted, ``judged`` saying what was checked of it."""
        out = []
        if self.known:
            out.append(f"{counted(sum(self.known.values()), 'frame', True)} of {counted(len(self.known), 'message')} "
                       "the suite does not cover "
                       f"({judged}): {_top(self.known)}")
        if self.undefined:
            out.append(f"{counted(sum(self.undefined.values()), 'frame', True)} of "
                       f"{counted(len(self.undefined), 'message id')} no definition "
                       f"the suite has names (a newer protocol, or a private message; {judged}, never a failure): "
                       f"{_top(self.undefined)}")
        return out


def _top(counts: Counter) -> str:
    top = ", ".join(f"{name} ({n:,})" for name, n in counts.most_common(LISTED))
    return top + (" ..." if len(counts) > LISTED else "")
