"""The shards of one selection (``run --shard K/N``, e.g. the jobs of a CI matrix) joined into the result the
whole selection would have given: every shard of the same run settings and provenance (tool, corpus, selection,
errata, waivers), each once, no case twice."""

from __future__ import annotations

from .bounds import SHARDS_MAX
from .causes import regrouped
from .results import MessageResult, RunResult, message_verdict
from .waivers import stale_note

SAME = ("suite", "title", "edition", "implementation", "adapter", "strict", "required")  # what the shards of one run share


def merge(results: list[RunResult], group_order: list[str], case_order: dict[str, int]) -> RunResult:
    """One result of the shards ``results``, messages in ``group_order`` and cases in ``case_order`` (the
    corpus's order, as an unsharded run has them); ValueError saying what does not fit."""
    if len(results) < 2:
        raise ValueError("give the results of every shard of the run (at least two)")
    first = results[0]
    for r in results:
        if r.shard is None:
            raise ValueError(f"a result of {r.implementation!r} is not a shard (it was run without --shard)")
        for key in SAME:
            if getattr(r, key) != getattr(first, key):
                raise ValueError(f"the shards differ in {key}: {getattr(first, key)!r} and {getattr(r, key)!r}")
        if r.provenance is None or first.provenance is None:
            raise ValueError("a shard records no provenance (a result of format 4 or before): run the shards again")
        for key in first.provenance.differences(r.provenance):
            raise ValueError(f"the shards differ in their {key}: {_shown(getattr(first.provenance, key))} and "
                             f"{_shown(getattr(r.provenance, key))}")
    n = first.shard[1]
    if not 2 <= n <= SHARDS_MAX:
        raise ValueError(f"a run of {n} shards: a selection is split into 2 to {SHARDS_MAX}")
    indices = sorted(r.shard[0] for r in results)
    if any(r.shard[1] != n for r in results) or len(set(indices)) != len(indices):
        raise ValueError(f"the shards are not each of one run of {n}: {', '.join(f'{r.shard[0]}/{r.shard[1]}' for r in results)}")
    missing = sorted(set(range(1, n + 1)) - set(indices))
    if missing:
        raise ValueError(f"shard{'s' if len(missing) > 1 else ''} {', '.join(f'{k}/{n}' for k in missing)} missing")
    seen: dict[str, int] = {}
    cases: dict[str, list] = {}
    for r in results:
        for m in r.messages:
            for c in m.cases:
                if c.id in seen:
                    raise ValueError(f"the case {c.id} is in shards {seen[c.id]}/{n} and {r.shard[0]}/{n}")
                seen[c.id] = r.shard[0]
                cases.setdefault(m.name, []).append(c)
    keys = {m.name: m.key for r in results for m in r.messages}
    rank = {name: i for i, name in enumerate(group_order)}
    messages = []
    for name in sorted(cases, key=lambda g: (rank.get(g, len(rank)), g)):
        ordered = sorted(cases[name], key=lambda c: (case_order.get(c.id, len(case_order)), c.id))
        messages.append(MessageResult(name, keys[name], message_verdict(ordered, first.strict), ordered))
    stale = sorted(set(results[0].stale_waivers).intersection(*(r.stale_waivers for r in results)))
    shard_stale = {stale_note(s, r.shard) for r in results for s in r.stale_waivers}  # stale in every shard, or not
    notes = list(dict.fromkeys(n for r in results for n in r.notes if n not in shard_stale))
    notes.insert(0, f"the {n} shards of the run merged")
    notes += [stale_note(s) for s in stale]
    return RunResult(first.suite, first.title, first.edition, first.implementation, first.adapter, first.strict,
                     min(r.started for r in results), round(sum(r.duration for r in results), 3), messages,
                     "".join(r.stderr for r in results), notes, all(r.complete for r in results),
                     [i for r in results for i in r.incidents],
                     sorted(set(results[0].untested).intersection(*(r.untested for r in results))),
                     provenance=first.provenance,
                     causes=regrouped([c for m in messages for c in m.cases], [g for r in results for g in r.cause_groups()]),
                     stale_waivers=stale, required=first.required)


def _shown(value, limit: int = 200) -> str:
    text = repr(value)
    return text if len(text) <= limit else text[:limit] + "..."
