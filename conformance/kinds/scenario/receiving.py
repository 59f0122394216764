"""What each kind of scenario step does with a reply it takes: an expected message, a sequence's state, a frame
breaking a silence, a sign of life, an acknowledged call."""

from __future__ import annotations

from .exchanges import States, resolved
from .matchers import hashable, same
from .records import StepState
from .values import resolve_plain
from .wire import Parsed


class Receiving:
    """The scenario machine's steps taking replies (a mixin of ``Machine``)."""

    def _on_accepted(self, t: float, step: StepState, problem: str | None) -> None:
        ref = step.spec["accepted"]
        self._find(step, "", problem is None, f"step {ref}'s call was accepted" if problem is None
                   else f"step {ref}'s call was refused: {problem}")

    def _on_expect(self, t: float, step: StepState, parsed: Parsed) -> None:
        spec = step.spec
        if "only" in spec and self._match_fields(spec["expect"], spec["only"], parsed) is not None:
            self._log(t, "ignored", parsed, "not what the step counts (its only)")
            return
        step.replies.append(parsed)
        self.scope.replies[spec["id"]] = parsed.fields
        self._log(t, "received", parsed, "matched")
        if len(step.replies) < spec.get("count", 1):
            return
        tries = f" (answered on try {step.tries})" if step.tries > 1 else ""
        self._find(step, "", True, f"{spec['expect']} received after {self._rel(t) - self._started(step):.3f} s{tries}")
        for name, level, clause, bad in self._correlate(step, parsed):
            self._find(step, name, bad is None, bad or "as required", level, clause)
        if spec.get("fields"):
            bad = self._match_fields(spec["expect"], spec["fields"], parsed)
            self._find(step, "fields", bad is None, bad or "fields as expected")
        for more in spec.get("also", ()):  # checks of the same reply at a weaker level: a SHOULD, or a reading
            bad = self._match_fields(spec["expect"], more["fields"], parsed)
            if more["level"] == "INFO":
                self._read(step, more["ambiguity"], f"{more['statement']}: " + (f"no ({bad})" if bad else "yes"))
            else:
                self._find(step, more["id"], bad is None, bad or more["statement"], more["level"], more["clause"])
        self._readings(step)

    def _on_sequence(self, t: float, step: StepState, parsed: Parsed) -> None:
        spec = step.spec
        states = self._states(step)
        field_ = states.field if states else None
        value = parsed.fields.get(field_)
        name = self._state_name(spec["sequence"], field_, value)
        step.replies.append(parsed)
        for check, level, clause, bad in self._correlate(step, parsed):
            _note(step, (check, level, clause), bad)
        if spec.get("fields"):
            _note(step, ("fields", spec.get("level", "MUST"), None), self._match_fields(spec["sequence"], spec["fields"], parsed))
        if states is None:
            return
        if "not_after" in spec:
            _note(step, ("not-after", spec.get("level", "MUST"), None), self._too_late(t, step, states, value, name))
        if step.terminal is not None:
            if step.open_end is None:
                _note(step, ("after-terminal", states.level, states.clause),
                      f"{name} after the terminal state {self._terminal_name(step)}")
                self._log(t, "received", parsed, f"{name}: after the terminal state")
                return
            self._read(step, step.open_end, f"{self._terminal_name(step)} was followed by {name}: read as a delay, "
                                            "not the end of the request")
            step.terminal, step.open_end = None, None
            step.until = max(step.bound, t + self._bound(spec.get("quiet", 1.0)))  # the request goes on: its own bound
        kind = states.kind(value)
        if kind == "unknown" and states.unknown is not None:
            self._read(step, states.unknown, f"{name} is not a state the definitions name for this request")
            kind, opened = "open", states.unknown
        else:
            opened = states.open.get(hashable(value))
        if kind in ("terminal", "open"):
            step.terminal, step.open_end = parsed, opened
            step.until = t + self._bound(spec.get("quiet", 1.0))
            if kind == "open":  # the request may still go on: listen until the step's own bound, the time it is given
                step.until = max(step.bound, step.until)
            self.released = self.released or (spec.get("release", False) and self._last_wait(step))
            self._log(t, "received", parsed, f"{name}: terminal state" if kind == "terminal" else
                      f"{name}: a state that may end the request or delay it (open reading {opened})")
        elif kind == "progress":
            self._log(t, "received", parsed, f"{name}: progress state")
        else:
            _note(step, ("states", states.level, states.clause),
                  f"{name} is neither a progress nor a terminal state of {spec['sequence']} for this request")
            self._log(t, "received", parsed, f"{name}: not a state of this exchange")

    def _too_late(self, t: float, step: StepState, states: States, value, name: str) -> str | None:
        """Why a reply breaks the step's ``not_after`` (a state that may not come later than a number of seconds
        after the request, the node's own seconds: not scaled), or None."""
        rule = step.spec["not_after"]
        names = resolved(self.wire, step.spec["sequence"], states.field, rule["states"], self.edition)
        if not any(same(value, v) for v in names):
            return None
        limit = float(resolve_plain(rule["seconds"], self.scope)) + self._seconds(rule.get("tolerance", 1.0))
        after = t - self.sent_at[step.spec["reply_to"]]
        return None if after <= limit else f"{name} {after:.3f} s after the request, later than {limit:g} s"

    def _on_silence(self, t: float, step: StepState, parsed: Parsed) -> None:
        ref = step.spec.get("reply_to")
        awaited = any(s.get("reply_to") == ref and ("expect" in s or "sequence" in s)
                      for s in self.program.scenario["steps"][:self.index])  # else no answer at all is allowed
        if ref is not None and awaited and self.answers[ref] <= self.sends[ref]:  # the request went more than once
            self._log(t, "received", parsed, f"an answer to one of the {self.sends[ref]} times the request was sent")
            return
        if "fields" in step.spec and self._match_fields(step.spec["silence"], step.spec["fields"], parsed) is not None:
            self._log(t, "ignored", parsed, "not what the silence is about (its fields)")
            return
        step.replies.append(parsed)
        self._log(t, "received", parsed, "breaks the expected silence")

    def _on_alive(self, t: float, step: StepState, parsed: Parsed) -> None:
        step.replies.append(parsed)
        self._log(t, "received", parsed, "the node is alive")
        self._find(step, "", True, f"{parsed.message} received after {self._rel(t) - self._started(step):.3f} s")


def _note(step: StepState, key: tuple, bad: str | None) -> None:
    """Keep the first failure of a check over all the replies of a sequence (None: passed so far)."""
    if step.failures.get(key) is None:
        step.failures[key] = bad
