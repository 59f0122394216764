"""What a scenario would send, without sending it (``run --dry-run``)."""

from __future__ import annotations

import itertools

from .machine import Program
from .values import Scope, Unresolved, resolve_message, resolve_plain
from .wire import Addressing


def planned_sends(program: Program, addressing: Addressing, epoch: float) -> list[tuple[str, dict | str]]:
    """(step id, the wire's description of what it sends, or why it cannot be built yet) for each send step."""
    counter = itertools.count(1000)
    scope = Scope(dict(program.params), lambda _name: next(counter), epoch,
                  addresses=addressing.symbols())
    out = []
    for step in program.scenario["steps"]:
        if "setup" in step:
            try:
                state = resolve_plain(step["setup"]["state"], scope)
            except Unresolved as exc:
                state = f"cannot be built before the run: {exc}"
            out.append((step["id"], {"setup": step["setup"]["service"], "state": state}))
            continue
        if "send" not in step:
            continue
        try:
            message = resolve_message(step["send"], scope, program.wire, program.edition)
            composed = program.wire.compose(message, step.get("encoding"), addressing, epoch, step["id"],
                                            program.edition)
        except (Unresolved, ValueError) as exc:
            out.append((step["id"], f"cannot be built before the run: {exc}"))
            continue
        scope.sent[step["id"]] = composed.decoded.get("fields", {})
        out.append((step["id"], program.wire.present(composed)))
    return out
