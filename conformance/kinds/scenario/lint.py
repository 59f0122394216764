"""Static checks of a scenario against the suite's definitions and exchanges file, when the corpus is read:
a mistake in a scenario is a corpus error (exit 2), never a verdict on the implementation."""

from __future__ import annotations

from .exchanges import exchange_for, silence_allowed
from .machine import Program
from .matchers import is_matcher, same
from .values import Scope, Unresolved, resolve_matcher, resolve_message, resolve_plain
from .wire import Addressing

WAITS = ("expect", "sequence", "silence", "alive")


def lint_scenario(case: dict, wire, behaviour: dict, editions, known, fields_of,
                  statements: dict, params: dict | None = None) -> tuple[str, str] | None:
    """(JSON path suffix, problem) for the first problem of ``case``, or None. ``known(message)``: whether the
    suite has the message; ``fields_of(message)``: its field names; ``statements``: the suite's behavioural
    statements by id (a step may cover only a testable one); ``params``: a run's parameters, to check that its
    messages can carry them (else each parameter's example)."""
    register = behaviour.get("ambiguities", {})
    for i, step in enumerate(case["steps"]):
        for key in ("covers", "exercises"):
            for j, sid in enumerate(step.get(key, ())):
                if sid not in statements:
                    return f".steps[{i}].{key}[{j}]", f"{sid!r} is not a statement of statements.json"
                if "untestable" in statements[sid]:
                    return f".steps[{i}].{key}[{j}]", f"{sid!r} is marked untestable in statements.json"
        if "if_silent" in step and step["if_silent"] not in register:
            return f".steps[{i}].if_silent", f"{step['if_silent']!r} is not an entry of ambiguities.json"
        if "if_silent" in step and "reply_to" in step:
            return (f".steps[{i}].if_silent", "a reply's silence is the exchange's to allow (exchanges.json silence), "
                                              "not a step's")
        problem = _normative_problem(step, statements)
        if problem:
            return f".steps[{i}]", problem
        for j, sid in enumerate(step.get("covers", ())):
            problem = _level_problem(step, statements[sid])
            if problem:
                return f".steps[{i}].covers[{j}]", problem
        for key, value in _bounds_of(step):
            problem = _bound_problem(value, behaviour.get("bounds"))
            if problem:
                return f".steps[{i}].{key}", problem
        for j, more in enumerate(step.get("also", ())):
            if more.get("ambiguity") is not None and more["ambiguity"] not in register:
                return f".steps[{i}].also[{j}].ambiguity", f"{more['ambiguity']!r} is not an entry of ambiguities.json"
            if step.get("level", "MUST") == "SHOULD" and more["level"] == "SHOULD":
                return f".steps[{i}].also[{j}].level", "also checks are weaker than their step: this step is a SHOULD already"
    for key, vocabulary in (("needs", "params"), ("effects", "effects")):
        for i, name in enumerate(case.get(key, ())):
            if name not in behaviour[vocabulary]:
                return f".{key}[{i}]", f"{name!r} is not one of the {vocabulary} of exchanges.json"
    if case.get("capability") not in behaviour["capabilities"]:
        return ".capability", f"{case.get('capability')!r} is not one of the capabilities of exchanges.json"
    expect = case["expect"]
    applies = [e for e in editions if isinstance(expect, str) or e in expect]
    unknown = set(expect) - set(editions) if isinstance(expect, dict) else set()
    if unknown:
        return ".expect", f"unknown edition {sorted(unknown)[0]!r}"
    for edition in applies:
        problem = _lint_steps(case, wire, behaviour, edition, known, fields_of, params, statements)
        if problem:
            return problem
    return None


def _lint_steps(case, wire, behaviour, edition, known, fields_of, params, statements):
    examples = {name: int(p["example"], 0) if p["type"] == "integer" else p["example"]
                for name, p in behaviour["params"].items()}
    examples.update(params or {})
    scope = Scope(examples, lambda _name: 1, 0.0, addresses={"system": 1, "node": 2, "other": 3, "stranger": 4, "late": 5})
    program = Program(case["id"], case, tuple(behaviour["exchanges"]), wire, edition, examples)
    seen, sends = set(), {}
    for i, step in enumerate(case["steps"]):
        where = f".steps[{i}]"
        if step["id"] in seen:
            return where + ".id", f"the step id {step['id']!r} appears twice"
        seen.add(step["id"])
        if ("setup" in step or "accepted" in step) and wire.transport != "call":
            return where, "setup and accepted steps are for handlers called through an adapter, not a live target"
        if ("as" in step or "to" in step) and wire.transport != "datagram":
            return where, "a second system (as, to) speaks on a live link, not through an adapter"
        if "setup" in step:
            try:
                resolve_plain(step["setup"]["state"], scope)
            except Unresolved as exc:
                return where + ".setup.state", str(exc)
            continue
        if "accepted" in step:
            if step["accepted"] not in sends:
                return where + ".accepted", f"{step['accepted']!r} is not an earlier send step"
            continue
        if "send" in step:
            message = step["send"]
            if not known(message["abbrev"]):
                return where + ".send.abbrev", f"unknown message {message['abbrev']!r}"
            try:
                resolved = resolve_message(message, scope, wire, edition)
                composed = wire.compose(resolved, step.get("encoding"), Addressing(1, 1, 2, 3, 4, 5).speaking_as(step.get("as")),
                                        0.0, step["id"], edition)
            except (Unresolved, KeyError, ValueError) as exc:
                return where + ".send", f"cannot be sent in {edition}: {exc}"
            scope.sent[step["id"]] = composed.decoded.get("fields", {})
            sends[step["id"]] = resolved
            continue
        kind = next((k for k in WAITS if k in step), None)
        if kind is None:
            continue
        message = step[kind]
        if message is not None and not known(message):
            return f"{where}.{kind}", f"unknown message {message!r}"
        ref = step.get("reply_to")
        if ref is not None:
            if ref not in sends:
                return where + ".reply_to", f"{ref!r} is not an earlier send step"
            exchange = program.exchange_for(sends[ref])
            if exchange is None:
                return where + ".reply_to", f"no exchange of exchanges.json opens with what step {ref!r} sends"
            problem = _silent_cover_problem(case, step, ref, sends, exchange, wire, edition, behaviour, statements)
            if problem:
                return where + ".covers", problem
            if exchange["reply"] != message:
                return f"{where}.{kind}", f"step {ref!r} opens the exchange {exchange['id']!r}, answered by {exchange['reply']}"
            if kind == "sequence" and "state" not in exchange:
                return where, f"the exchange {exchange['id']!r} has no states for a sequence"
            if kind == "sequence":
                states = exchange["state"]
                names = {*states["progress"], *states["terminal"], *states.get("open", {})}
                names |= {n for v in states.get("by_request", {}).get("values", {}).values()
                          for n in (*v.get("progress", ()), *v.get("terminal", ()), *v.get("open", {}))}
                opened = [*states.get("open", {}).values(), *([states["unknown"]] if "unknown" in states else ())]
                opened += [rule["ambiguity"] for rule in exchange.get("silence", ())]
                opened += [a for v in states.get("by_request", {}).get("values", {}).values() for a in v.get("open", {}).values()]
                register = behaviour.get("ambiguities", {})
                for ambiguity in opened:
                    if ambiguity not in register:
                        return where, f"the exchange {exchange['id']!r} cites {ambiguity!r}, not an entry of ambiguities.json"
                if "not_after" in step:
                    try:
                        float(resolve_plain(step["not_after"]["seconds"], scope))
                    except (Unresolved, TypeError, ValueError) as exc:
                        return f"{where}.not_after.seconds", f"not a number of seconds: {exc}"
                for name in (*step.get("on_state", {}), *step.get("not_after", {}).get("states", ())):
                    if name not in names:
                        key = "on_state" if name in step.get("on_state", {}) else "not_after.states"
                        return f"{where}.{key}.{name}", f"{name!r} is not a state of the exchange {exchange['id']!r}"
            if step.get("release"):
                problem = _release_problem(case, i, ref, exchange)
                if problem:
                    return where + ".release", problem
        elif kind == "sequence":
            return where, "a sequence needs reply_to"
        matchers = [(key, step.get(key, {})) for key in ("fields", "only", "terminal")]
        matchers += [(f"on_state.{state}", more) for state, more in step.get("on_state", {}).items()]
        for key, specs in matchers:
            for name, spec in specs.items():
                if name not in fields_of(message):
                    return f"{where}.{key}.{name}", f"{message} has no field {name!r}"
                try:
                    resolve_matcher(spec, message, name, scope, wire, edition)
                except (Unresolved, KeyError) as exc:
                    return f"{where}.{key}.{name}", f"{exc}"
                if is_matcher(spec) and "one_of" in spec and not resolve_matcher(spec, message, name, scope, wire, edition)["one_of"]:
                    return f"{where}.{key}.{name}", f"no value of one_of exists in {edition}"
        if message is not None and kind in ("expect", "sequence"):
            scope.replies[step["id"]] = wire.example(message, edition)  # what a later step's $reply reads
    return None


ORDER = ("INFO", "SHOULD", "MUST")


def _level_problem(step: dict, statement: dict) -> str | None:
    """Why a step may not call a statement checked (``covers``): the behaviour-coverage table calls a statement
    checked only where a step fails (or, for a SHOULD, flags) a node that breaks it, so the step must judge at the
    statement's level or above and must not let silence pass (``if_silent``); otherwise the step ``exercises`` it."""
    level = step.get("level", "MUST")
    if ORDER.index(level) < ORDER.index(statement["level"]):
        return (f"{statement['id']!r} is a {statement['level']} statement and this step judges at {level}: it does not "
                "assert it at its level (list it under exercises)")
    if "if_silent" in step:
        return (f"this step lets silence pass ({step['if_silent']}), so a node that never does what "
                f"{statement['id']!r} says passes: list it under exercises")
    return None


def _silent_cover_problem(case, step, ref, sends, exchange, wire, edition, behaviour, statements) -> str | None:
    """Why a reply step may not call its statements checked: the exchange lets the request go unanswered (its
    ``silence`` rules, or those for every request), so a node that never answers passes; where the register weighs
    that silence as a SHOULD not met (NON_STRICT), it still asserts the statements of level SHOULD or below."""
    if not step.get("covers") or "silence" in step:
        return None
    spec = next(s for s in case["steps"] if s["id"] == ref)
    fields = sends[ref]["fields"]
    nobody = {n for n, v in spec["send"]["fields"].items() if isinstance(v, dict) and "$nobody" in v}
    order = [s["id"] for s in case["steps"]]
    earlier = [sends[s]["fields"] for s in sends if order.index(s) < order.index(ref)
               and exchange is _exchange_of(sends[s], behaviour, wire, edition)]
    reuses = {r["request_field"] for r in exchange.get("correlation", ()) if r["kind"] == "echo"
              and any(same(e.get(r["request_field"]), fields.get(r["request_field"])) for e in earlier)}
    kind = [sends[s]["fields"] for s in sends if order.index(s) < order.index(ref)
            and sends[s]["abbrev"] == sends[ref]["abbrev"]]
    answered = any(s.get("reply_to") == ref and order.index(s["id"]) < order.index(step["id"]) for s in case["steps"])
    facts = {"nobody": nobody, "reuses": reuses, "to": "elsewhere" if spec.get("to") not in (None, "node") else None,
             "earlier": kind, "copied": spec.get("copies", 1) > 1 and answered}
    ambiguity = silence_allowed(wire, exchange, fields, edition, facts, behaviour.get("silence", ()))
    if ambiguity is None:
        return None
    weighed = behaviour.get("ambiguities", {}).get(ambiguity, {}).get("level", "INFO")
    unmet = [sid for sid in step["covers"] if ORDER.index(statements[sid]["level"]) > ORDER.index(weighed)]
    if not unmet:
        return None
    return (f"the seeds let {ref!r} go unanswered ({ambiguity}), so a node that never answers passes: list "
            f"{', '.join(map(repr, unmet))} under exercises")


def _exchange_of(message: dict, behaviour: dict, wire, edition: str):
    return exchange_for(behaviour["exchanges"], wire, message, edition)


def _bounds_of(step: dict):
    """(key, value) of every timing bound a step gives."""
    for key in ("within", "for", "wait", "quiet", "queued"):  # queued: a robustness probe's, per request queued
        if key in step:
            yield key, step[key]
    if "not_after" in step:  # its default, 1 s, is a number too: where the suite has a register, a bound is named
        yield "not_after.tolerance", step["not_after"].get("tolerance", 1.0)


def _bound_problem(value, bounds: dict | None) -> str | None:
    """Why a timing bound cannot stand: where the suite has a register of bounds, each names one of them (and so
    where it comes from); where it has none, it is seconds."""
    if bounds is None:
        return None if not isinstance(value, str) else f"{value!r}: this suite has no register of bounds; give seconds"
    if isinstance(value, str) and value in bounds:
        return None
    return (f"{value!r} is not one of the bounds of exchanges.json: a timing bound names its source "
            f"({', '.join(bounds)})")


def _release_problem(case: dict, index: int, ref: str, exchange: dict) -> str | None:
    """Why a sequence may not release its resources early: replies not tied to the request by a unique value,
    or steps after it that still wait."""
    if any(k in later for later in case["steps"][index + 1:] for k in ("send", "setup", *WAITS, "accepted")):
        return "only the last step that waits may release the scenario's resources"
    fields = next(s for s in case["steps"] if s["id"] == ref)["send"]["fields"]
    unique = [r for r in exchange["correlation"] if r["kind"] == "echo"
              and isinstance(fields.get(r["request_field"]), dict) and "$unique" in fields[r["request_field"]]]
    return None if unique else (f"the exchange {exchange['id']!r} ties replies to step {ref!r} by no $unique value, "
                                "so another scenario's replies could be taken for its own")


def _normative_problem(step: dict, statements: dict) -> str | None:
    """Why a step that waits may not be MUST: a MUST step must cover a MUST statement (statements.json quotes the
    seed's words; a MUST statement rests on shall/must, a named reply or a correlating field) or, for a step that
    only exercises what a MUST statement names, cite one; a step that covers nothing testable is not judged."""
    if not any(k in step for k in WAITS) or step.get("level", "MUST") != "MUST":
        return None
    cited = [*step.get("covers", ()), *step.get("exercises", ())]
    if any(statements[sid]["level"] == "MUST" for sid in cited if sid in statements):
        return None
    return ("a MUST step must cover (or exercise) a MUST statement of statements.json, whose words are the seed's "
            "normative text; cite one, or make the step SHOULD")
