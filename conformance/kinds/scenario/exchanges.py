"""Reading a suite's exchange rules (exchanges.json): which exchange a request opens, the values a rule names,
resolved through the suite's wire, when the seeds let a request go unanswered, and the timing bounds rules and
steps name."""

from __future__ import annotations

from dataclasses import dataclass

from .matchers import hashable, same


def resolved(wire, message: str, path: str, names, edition: str) -> list:
    """What the wire carries for each of ``names`` of field ``path`` (names the edition lacks left out)."""
    out = []
    for name in names:
        try:
            out.append(wire.resolve(message, path, name, edition))
        except KeyError:
            continue
    return out


def selected(wire, message: str, fields: dict, when: dict, edition: str) -> bool:
    """Whether ``fields`` hold one of the values ``when`` names for each of its fields."""
    return all(fields.get(f) in resolved(wire, message, f, names, edition) for f, names in when.items())


def silence_allowed(wire, exchange: dict, request: dict, edition: str, facts: dict | None = None,
                    everywhere=(), unended: bool = False) -> str | None:
    """The ambiguity under which the seeds define no reply to this request (a rule of the exchange's ``silence``,
    or of ``everywhere``: the rules for every exchange), or None. A rule selects requests by their fields (``when``,
    ``null``) and by ``facts`` about them: the fields naming a system nobody answers for (``nobody``), the fields
    whose value an earlier request of the exchange still carries (``reuses``), the fields whose value a later
    request carries that was answered (``reused``: it may have replaced this one), where the request was addressed
    (``to``: "elsewhere", neither the node nor anyone), the fields of the earlier messages of its kind from the
    same requester (``earlier``: a rule's ``after`` selects a request one of them, echoing its values, undid), and
    whether it was sent in copies, one of them answered already (``copied``: a further reply is the copy's to give).
    ``unended``: the rules under which a request may also be left without its end (its replies stop before a
    terminal state), those marked ``unended``."""
    facts = facts or {}
    message = exchange["request"]["message"]
    for rule in (*exchange.get("silence", ()), *everywhere):
        if unended and not rule.get("unended"):
            continue
        if (selected(wire, message, request, rule.get("when", {}), edition)
                and ("reused" not in rule or rule["reused"] in facts.get("reused", ()))
                and ("null" not in rule or request.get(rule["null"]) is None)
                and ("nobody" not in rule or rule["nobody"] in facts.get("nobody", ()))
                and ("reuses" not in rule or rule["reuses"] in facts.get("reuses", ()))
                and ("to" not in rule or rule["to"] == facts.get("to"))
                and ("copied" not in rule or rule["copied"] == bool(facts.get("copied")))
                and ("after" not in rule or any(selected(wire, message, e, rule["after"], edition)
                                                and _echoes(exchange, e, request) for e in facts.get("earlier", ())))):
            return rule["ambiguity"]
    return None


def _echoes(exchange: dict, earlier: dict, request: dict) -> bool:
    """Whether an earlier message carried the request's values of every field the exchange's replies echo."""
    fields = [r["request_field"] for r in exchange.get("correlation", ()) if r["kind"] == "echo"]
    return bool(fields) and all(same(earlier.get(f), request.get(f)) for f in fields)


def seconds(value, bounds: dict) -> float:
    """A timing bound in seconds: a number, or the name of one of the suite's ``bounds`` (exchanges.json), each
    saying where it comes from."""
    return float(bounds[value]["seconds"] if isinstance(value, str) else value)


def exchange_for(exchanges, wire, message: dict, edition: str) -> dict | None:
    """The exchange a message (decoded form, values resolved) opens as a request, if any."""
    for ex in exchanges:
        request = ex["request"]
        if request["message"] == message["abbrev"] and selected(wire, message["abbrev"], message["fields"],
                                                                 request.get("when", {}), edition):
            return ex
    return None


@dataclass(frozen=True)
class States:
    """The states of an exchange's replies for one request, as the wire carries them: ``progress`` (under way),
    ``terminal`` (ending it: exactly one, nothing after), ``open`` (value -> ambiguity id: the seeds leave open
    whether the state ends the request or delays it, so a sequence may end on it or go on), ``unknown`` (the
    ambiguity id reading any other value as an open state rather than a failure, or None); ``declined``: the
    terminal states that decline the request where the seeds let a node (the operation is not supported), with the
    ``declined_clause`` they rest on; ``level`` and ``clause``: what the rules of one terminal, nothing after it and
    known states rest on."""

    field: str
    progress: frozenset
    terminal: frozenset
    open: dict
    unknown: str | None
    level: str
    clause: str
    declined: frozenset = frozenset()
    declined_clause: str | None = None

    def kind(self, value) -> str:
        """``progress``, ``terminal``, ``open`` or ``unknown`` for a reply's state value."""
        value = hashable(value)
        if value in self.terminal:
            return "terminal"
        if value in self.progress:
            return "progress"
        return "open" if value in self.open else "unknown"


def states_for(wire, exchange: dict, request: dict, edition: str) -> States | None:
    """The states of ``exchange``'s replies to a request with fields ``request`` (its ``by_request`` entry for
    the request's value, where it has one), or None for an exchange without states."""
    state = exchange.get("state")
    if state is None:
        return None
    chosen = dict(state)
    by = state.get("by_request")
    if by is not None:
        message = exchange["request"]["message"]
        value = request.get(by["field"])
        for name, override in by["values"].items():
            if any(same(value, v) for v in resolved(wire, message, by["field"], [name], edition)):
                chosen.update(override)  # (a name the edition lacks resolves to nothing and selects nothing)
                break

    def values(names) -> frozenset:
        return frozenset(hashable(v) for v in resolved(wire, exchange["reply"], state["field"], names, edition))

    opened = {}
    for name, ambiguity in chosen.get("open", {}).items():
        for v in values([name]):
            opened[v] = ambiguity
    declined = chosen.get("declined", {})
    return States(state["field"], values(chosen["progress"]) - opened.keys(), values(chosen["terminal"]) - opened.keys(),
                  opened, chosen.get("unknown"), chosen.get("level", "MUST"), chosen["clause"],
                  values(declined.get("states", ())), declined.get("clause"))


def weaker(a: str, b: str) -> str:
    """The weaker of two levels (MUST, SHOULD, INFO)."""
    order = ("INFO", "SHOULD", "MUST")
    return min(a, b, key=order.index)
