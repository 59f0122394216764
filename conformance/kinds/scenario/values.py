"""Resolving the values a scenario writes symbolically: parameters, per-run unique numbers, times, what an
earlier step sent, addresses, names of systems nobody answers for, and names (enumeration values) through the
suite's wire."""

from __future__ import annotations

from dataclasses import dataclass, field

from .matchers import KEYS, is_matcher

SYMBOLS = ("$param", "$unique", "$epoch", "$sent", "$reply", "$address", "$nobody")


class Unresolved(Exception):
    """A value cannot be resolved: a parameter not given (``param``) or a name the edition lacks."""

    def __init__(self, what: str, param: str | None = None):
        super().__init__(what)
        self.param = param


@dataclass
class Scope:
    """What symbols resolve to in one scenario: ``params`` of the run, ``unique(name)`` numbers, ``epoch``
    now, the decoded fields each send step sent (``sent[step]``), those of the reply each step matched last
    (``replies[step]``), and ``addresses``."""

    params: dict
    unique: object  # callable name -> int
    epoch: float = 0.0
    sent: dict = field(default_factory=dict)
    replies: dict = field(default_factory=dict)
    addresses: dict = field(default_factory=dict)  # "system" (the session's), "node", "other", "stranger", "late"

    def symbol(self, spec: dict):
        (key, arg), = spec.items()
        if key == "$param":
            if arg not in self.params:
                raise Unresolved(f"needs --param {arg}=...", arg)
            return self.params[arg]
        if key == "$unique":
            return self.unique(arg)
        if key == "$epoch":
            return self.epoch + arg
        if key == "$nobody":  # a name no system answers to: the exchange's silence rules may read it so
            return arg
        if key == "$address":
            if self.addresses.get(arg) is None:
                raise Unresolved(f"the {arg}'s address is not known")
            return self.addresses[arg]
        step, _, path = arg.partition(".")
        source = self.sent if key == "$sent" else self.replies
        if step not in source:
            raise Unresolved(f"{key} {arg}: step {step!r} has {'sent' if key == '$sent' else 'matched'} nothing")
        value = source[step]
        try:
            for part in path.split(".") if path else ():
                value = value[int(part)] if isinstance(value, list) else value[part]
        except (KeyError, IndexError, ValueError, TypeError):
            raise Unresolved(f"{key} {arg}: no such field in what step {step!r} {'sent' if key == '$sent' else 'matched'}") from None
        return value


def is_symbol(spec) -> bool:
    return isinstance(spec, dict) and len(spec) == 1 and next(iter(spec)) in SYMBOLS


def resolve_message(message: dict, scope: Scope, wire, edition: str) -> dict:
    """A send step's message with every symbol and name resolved (inline messages too)."""
    name = message["abbrev"]
    out = {"abbrev": name, "fields": {k: resolve_value(v, name, k, scope, wire, edition)
                                       for k, v in message.get("fields", {}).items()}}
    if "header" in message:
        out["header"] = {k: scope.symbol(v) if is_symbol(v) else v for k, v in message["header"].items()}
    return out


def resolve_plain(value, scope: Scope):
    """A JSON value with every symbol in it resolved (no names: it is not a message)."""
    if is_symbol(value):
        return scope.symbol(value)
    if isinstance(value, dict):
        return {k: resolve_plain(v, scope) for k, v in value.items()}
    if isinstance(value, list):
        return [resolve_plain(v, scope) for v in value]
    return value


def resolve_value(value, message: str, path: str, scope: Scope, wire, edition: str):
    if is_symbol(value):
        return scope.symbol(value)
    if isinstance(value, dict) and "abbrev" in value:
        return resolve_message(value, scope, wire, edition)
    if isinstance(value, list):
        return [resolve_value(v, message, path, scope, wire, edition) for v in value]
    try:
        return wire.resolve(message, path, value, edition)
    except KeyError as exc:
        raise Unresolved(f"{message}.{path}: {exc.args[0]}") from None


def resolve_matcher(spec, message: str, path: str, scope: Scope, wire, edition: str):
    """A matcher with its values resolved; in ``one_of``, names the edition lacks are left out (a state the
    edition does not have cannot arrive)."""
    if not is_matcher(spec):
        return resolve_value(spec, message, path, scope, wire, edition)
    (key, arg), = ((k, v) for k, v in spec.items() if k in KEYS)
    if key in ("one_of", "none_of"):
        kept = []
        for v in arg:
            try:
                kept.append(resolve_value(v, message, path, scope, wire, edition))
            except Unresolved as exc:
                if exc.param:
                    raise
        return {key: kept}
    if key in ("equal", "contains_item"):
        return {**spec, key: resolve_value(arg, message, path, scope, wire, edition)}
    if key in ("all_of", "any_of"):
        return {key: [resolve_matcher(m, message, path, scope, wire, edition) for m in arg]}
    if key in ("contains_message", "lacks_message") and isinstance(arg, dict):  # the symbols among its fields
        return {key: {**arg, "fields": resolve_plain(arg.get("fields", {}), scope)}}
    return spec
