"""Failures grouped by cause across messages: what a reader fixes, rather than what a case id names.

A case that fails (or, NON_STRICT, names the wrong rule or falls short of a SHOULD) has one cause: what it is about (the rule its input breaks,
the implementation-defined class it belongs to; else "valid input", whatever value class it exercises, since one
defect fails valid cases of many classes, or the family of a case of another kind, the third segment of its id) and
what went wrong with it (accepted what breaks the rule, a check that fails, a crash); a capture's or a log's case
is about what was recorded (frames that break a rule, exchanges that fail a check).
Cases with the same cause form a group, whatever message they are filed under; groups come largest first, each with
its cases, its messages and the errata that explain its cases (an implementation without errata gets the same
groups). Suite-generic: the causes come from the case's data (``rule``, ``class``), or, for a result read back
without them, from what the result keeps (``rule``, the expectation, the id).
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass
from typing import Callable, Iterable

from .verdicts import Verdict, failing

SHOWN_IN_TITLE = 3  # ops or classes named in a title before "…"
RECORDED = {"frame": "frames", "exchange": "exchanges", "connection": "connections"}  # what a capture's or a log's
# cases are about (``<suite>/<group>/capture/<kind>/...``): they judge what was recorded, not an implementation's answer
VERBS = {Verdict.CRASH: "crashes on", Verdict.TIMEOUT: "times out on", Verdict.ADAPTER_ERROR: "adapter error on"}


@dataclass(frozen=True)
class Cause:
    """One group: ``key`` (stable, e.g. ``accepts/rule:crc``), ``title`` (plain words), its ``cases`` (ids, run
    order), the ``messages`` they are filed under, ``errata`` (id, cases it explains; most first) and ``verdicts``."""

    key: str
    title: str
    cases: tuple[str, ...]
    messages: tuple[str, ...]
    errata: tuple[tuple[str, int], ...] = ()
    verdicts: tuple[tuple[str, int], ...] = ()

    @property
    def summary(self) -> str:
        """e.g. "828 cases in 31 messages, first imc/Heartbeat/crc/header-timestamp/le"."""
        n, m = len(self.cases), len(self.messages)
        return (f"{n} case{'s' if n != 1 else ''} in {m} message{'s' if m != 1 else ''}, first {self.cases[0]}")

    def to_dict(self) -> dict:
        return {"key": self.key, "title": self.title, "cases": list(self.cases), "messages": list(self.messages),
                "errata": dict(self.errata), "verdicts": dict(self.verdicts)}


# What a cause key of a judged case begins with (cause_of), and whether the operations that failed come next
# ("fails/decode/valid") or what its cases are about does ("accepts/rule:crc")
BEGINNINGS = {"accepts": False, "names-another-rule": False, "not-permitted": False, "should": True, "fails": True,
              **{v.value.lower(): True for v in VERBS}}


def key_problem(key: str, subjects: set[str]) -> str | None:
    """Why ``key`` is not the cause key of a judged case (its beginning, its shape, or what it says its cases are
    about, which must be one of ``subjects``), or None."""
    parts = key.split("/")
    if parts[0] not in BEGINNINGS:
        return f"it begins with {parts[0]!r}, not one of {', '.join(sorted(BEGINNINGS))}"
    shape = f"{parts[0]}/OPERATIONS/SUBJECT" if BEGINNINGS[parts[0]] else f"{parts[0]}/SUBJECT"
    if len(parts) != (3 if BEGINNINGS[parts[0]] else 2) or not all(parts):
        return f"a key beginning with {parts[0]!r} is {shape}"
    if parts[-1] not in subjects:
        return f"no case of this corpus is about {parts[-1]!r}"
    return None


def attended(verdict: Verdict) -> bool:
    """The verdicts a cause is looked for: every failing one (whatever --strict says) and NON_STRICT."""
    return failing(verdict, strict=False) or verdict is Verdict.NON_STRICT


def about(case, data: dict | None = None) -> tuple[str, str]:
    """(key, words) of what a case is about: its rule, its class, else "valid input" or its family (a scenario's)."""
    data = data or {}
    rule = data.get("rule", case.rule)
    if rule:
        return f"rule:{rule}", f"rule {rule}"
    named = data.get("class")
    if named:
        named = "+".join(named) if isinstance(named, list) else named
        return f"class:{named}", f"class {named}"
    if case.expect == "valid":  # one defect fails valid cases of every value class: they are one cause
        return "valid", "valid input"
    family = case.id.split("/")[2] if case.id.count("/") >= 2 else case.id
    return f"family:{family}", family


def subjects(cases) -> set[str]:
    """Every key ``about`` can give the corpus's cases (``cases``: core.cases.Case): what a cause key may end with."""
    out = {"valid", "family:passive"}  # what every case kind may file under another group (core.cases.passive_id)
    for case in cases:
        rule, named = case.data.get("rule"), case.data.get("class")
        if rule:
            out.add(f"rule:{rule}")
        elif named:
            out.add(f"class:{'+'.join(named) if isinstance(named, list) else named}")
        else:
            out.add(f"family:{case.id.split('/')[2] if case.id.count('/') >= 2 else case.id}")
    return out


def ops(case) -> list[str]:
    """The operations of the checks that gave the case its verdict (decode, encode, roundtrip, a step's name)."""
    worst = [c.check for c in case.checks if c.verdict == case.verdict] or [c.check for c in case.checks]
    return list(dict.fromkeys(check.split("-", 1)[0] for check in worst))


def cause_of(case, data: dict | None = None) -> tuple[str, str] | None:
    """(key, title) of a case's cause, or None for a case that needs none (it passes, or is waived)."""
    verdict = case.verdict
    if not attended(verdict):
        return None
    if verdict is Verdict.WAIVER_STALE:
        return "waiver-stale", "waived, but passes now: the waiver must go"
    key, words = about(case, data)
    parts = case.id.split("/", 4)
    if len(parts) > 3 and parts[2] == "capture" and parts[3] in RECORDED:  # what recorded traffic or a log holds
        what = key if key.startswith("rule:") else parts[3] + ("/" + parts[4] if len(parts) > 4 else "")
        return f"recorded/{what}", (f"recorded {RECORDED[parts[3]]} that break {words}" if key.startswith("rule:")
                                    else f"recorded {RECORDED[parts[3]]} that fall short of a SHOULD: {parts[-1]}"
                                    if verdict is Verdict.NON_STRICT else f"recorded {RECORDED[parts[3]]} that fail "
                                    f"{parts[-1]}")
    did = "+".join(ops(case)[:SHOWN_IN_TITLE]) or "the case"
    if verdict in VERBS:
        return f"{verdict.value.lower()}/{did}/{key}", f"{VERBS[verdict]} {did}: {words}"
    if verdict is Verdict.NON_STRICT and key.startswith("rule:"):  # an input breaking a rule, refused for another
        return f"names-another-rule/{key}", f"refuses, but names another rule than it breaks: {words}"
    if verdict is Verdict.NON_STRICT:  # behaviour: what a SHOULD asks, not done
        return f"should/{did}/{key}", f"{did} falls short of a SHOULD: {words}"
    if key.startswith("rule:"):
        action = "accepts" if did in ("decode", "roundtrip") else "encodes" if did == "encode" else f"{did} passes"
        return f"accepts/{key}", f"{action} what breaks {words}"
    if key.startswith("class:"):
        return f"not-permitted/{key}", f"{did}: an outcome {words} does not permit"
    return f"fails/{did}/{key}", f"{did} fails on {words}"


def group_causes(cases: Iterable, cause: Callable[[object], tuple[str, str] | None] = cause_of,
                 errata: bool = True, describe: Callable[[str, str, list], str] | None = None) -> list[Cause]:
    """The cases' causes (``cause(case)``: (key, title) or None), grouped, largest first (then by key);
    ``describe(key, title, members)``: the group's title, naming what its cases share (``described``)."""
    groups: dict[str, tuple[str, list]] = {}
    for case in cases:
        found = cause(case)
        if found is not None:
            groups.setdefault(found[0], (found[1], []))[1].append(case)
    out = []
    for key, (title, members) in groups.items():
        if describe is not None:
            title = describe(key, title, members)
        explained = Counter(e for c in members for e in c.errata) if errata else Counter()
        out.append(Cause(key, title, tuple(c.id for c in members), tuple(dict.fromkeys(c.message for c in members)),
                         tuple(explained.most_common()), tuple(sorted(Counter(c.verdict.value for c in members).items()))))
    return sorted(out, key=lambda g: (-len(g.cases), g.key))


def regrouped(cases: Iterable, known: Iterable[Cause]) -> list[Cause]:
    """The groups of ``cases`` as ``known`` groups (read back, or of shards) put them; a case they do not name gets
    the cause its result alone tells."""
    named = {case_id: (g.key, g.title) for g in known for case_id in g.cases}
    return group_causes(cases, lambda case: (named.get(case.id) or cause_of(case)) if attended(case.verdict) else None)


def cause_from(doc: dict) -> Cause:
    """A group as a saved result holds it (its cases are regrouped against the result's own cases on reading)."""
    return Cause(doc["key"], doc["title"], tuple(doc["cases"]), tuple(doc["messages"]),
                 tuple(doc.get("errata", {}).items()), tuple(doc.get("verdicts", {}).items()))


DESCRIBED = ("fails/", "not-permitted/")  # the causes whose title says what their cases share, where it can be told
SHOWN_PATHS = 3  # fields named in a title before "… (N fields)"
REFUSAL_WORDS = 80  # characters of the words refusals share, quoted in a title


def described(key: str, title: str, members: list, data: dict, differences: Callable[[object], list]) -> str:
    """A title naming the difference a group's cases share: their value classes (the case data's ``class:`` tags),
    the one value the implementation gave in their place, the fields that differ; for refusals, the types every case
    holds and the words every refusal begins with. ``differences(case)``: (path, expected, answered) of its failing
    checks, as the case kind reads them; ``data``: the cases' data, by id."""
    if not key.startswith(DESCRIBED):
        return title
    parts = []
    classes = [sorted(t[6:] for t in data.get(c.id, {}).get("tags", ()) if t.startswith("class:")) for c in members]
    if all(classes):
        named = list(dict.fromkeys(x for found in classes for x in found))
        parts.append("class " + " or ".join(named[:SHOWN_IN_TITLE]) + (" …" if len(named) > SHOWN_IN_TITLE else ""))
    found = [d for c in members for d in differences(c)]
    if found:
        answered = {repr(a) for _, _, a in found}
        if len(answered) == 1:
            did = set(ops(members[0])) if all(set(ops(c)) == set(ops(members[0])) for c in members) else set()
            verb = "written" if did and did <= {"encode", "roundtrip"} else "read" if did == {"decode"} else "answered"
            parts.append(f"{verb} as {answered.pop()}")
        paths = list(dict.fromkeys(p for p, _, _ in found))
        shown = ", ".join(paths[:SHOWN_PATHS])
        parts.append(f"in {shown}" + (f" … ({len(paths)} fields)" if len(paths) > SHOWN_PATHS else ""))
    else:
        held = [set(data.get(c.id, {}).get("definitions", ())) for c in members]
        common = sorted(set.intersection(*held)) if held and all(held) else []
        own = {c.message for c in members}
        if common and set(common) != own:
            parts.append("holding " + ", ".join(common[:SHOWN_IN_TITLE]))
        refusals: dict[str, list[str]] = {}  # by operation: the words of each refusal
        for c in members:
            for k in c.checks:
                if k.verdict is Verdict.FAIL and k.detail.startswith("refused"):
                    refusals.setdefault(k.check.split("-", 1)[0], []).append(k.detail.split(": ", 1)[-1])
        prefix = max((_common_prefix(texts) for texts in refusals.values()), key=len, default="")
        if len(prefix) >= 12:
            parts.append(f"refused: {prefix[:REFUSAL_WORDS]}{'…' if len(prefix) > REFUSAL_WORDS else ''}")
    return f"{title}: {'; '.join(parts)}" if parts else title


def _common_prefix(texts: list[str]) -> str:
    if not texts:
        return ""
    first, last = min(texts), max(texts)
    n = next((i for i, (a, b) in enumerate(zip(first, last)) if a != b), min(len(first), len(last)))
    return first[:n].rstrip()
