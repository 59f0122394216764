"""ros_acomms service handlers as scenario targets: a scenario's send step becomes a call of the handler under
test (a service request) or a publish to it (a message such as UpdateQueuedMessage), through the adapter; the
call's answer is the reply. Fields a step leaves out take their ROS defaults; constants may be given by name."""

from __future__ import annotations

from ...kinds.scenario import Composed, Parsed
from . import codec, forms
from .corpus.values import default, fields as default_fields
from .definitions import PRIMITIVES, RosDefinitions, TypeDef


class RosWire:
    transport = "call"
    anyone = None

    def __init__(self, defs: RosDefinitions):
        self.defs = defs
        self.by_name = {t.name: t for t in defs.suite_types}

    def type_of(self, name: str) -> TypeDef:
        if name not in self.by_name:
            raise KeyError(f"{name} is not a type of ros_acomms_msgs")
        return self.by_name[name]

    def knows(self, message: str) -> bool:
        return message in self.by_name

    def fields_of(self, message: str) -> list[str]:
        return [f.name for f in self.type_of(message).fields]

    def reply_type(self, request: TypeDef) -> TypeDef:
        return self.type_of(f"{request.service}Response")

    def compose(self, message: dict, encoding, addressing, epoch: float, step: str = "", edition: str | None = None):
        """A call of the handler (service request) or a publish to it (message), with defaults filled."""
        t = self.type_of(message["abbrev"])
        view = self.defs.edition(edition or self.defs.editions[0])
        if t.full not in view:
            raise ValueError(f"{t.name} is not a type of edition {view.name}")
        filled = {**default_fields(view, t.full, default), **message["fields"]}
        decoded = {"type": t.full, "fields": filled}
        problem = forms.message_problem(view, decoded, strict=True)
        if problem:
            raise ValueError(f"{t.name}{problem[0]}: {problem[1]}")
        if t.kind == "request":
            data = {"op": "call", "service": t.service, "request": decoded}
        elif t.kind == "msg":
            data = {"op": "publish", "type": t.full, "message": decoded}
        else:
            raise ValueError(f"{t.name} is a response: a handler answers it, a scenario cannot send it")
        return Composed(data, {"fields": filled}, t.name, None, {"step": step, "edition": view.name})

    def setup(self, service: str, state: dict, step: str) -> Composed:
        if not any(t.service == service for t in self.by_name.values()):
            raise ValueError(f"{service} is not a service of ros_acomms_msgs")
        return Composed({"op": "setup", "service": service, "state": state}, {"fields": state}, service, None,
                        {"step": step})

    def reply(self, composed: Composed, answer) -> Parsed | None:
        """The response a call's answer carries (a publish or a setup only acknowledges). A response not in
        the decoded form at all is the adapter's fault (ValueError); one whose fields differ from the
        definition, or hold values their types cannot, is the handler's (a malformed reply)."""
        if composed.data["op"] != "call":
            return None
        view = self.defs.edition(composed.extra["edition"])
        expected = self.reply_type(self.type_of(composed.message))
        problem = forms.message_problem(view, answer, strict=False, expect_type=expected.full)
        if problem:
            raise ValueError(f"malformed response: message{problem[0]}: {problem[1]}")
        problem = forms.message_problem(view, answer, strict=True, expect_type=expected.full)
        if problem:
            return Parsed(answer, expected.name, None, f"message{problem[0]}: {problem[1]}", expected.clause)
        return Parsed(answer, expected.name, {"fields": answer["fields"]})

    def parse(self, data) -> Parsed:
        raise ValueError("a handler answers calls; nothing arrives on its own")

    def resolve(self, message: str, path: str, value, edition: str):
        """A constant's name (``QUEUE_IMMEDIATE``, ``EVENT_LINK_QUEUED``) as its value, for a numeric field."""
        t = self.type_of(message)
        field = next((f for f in t.fields if f.name == path), None)
        if not isinstance(value, str) or field is None or field.type.base not in PRIMITIVES or field.type.array is not None:
            return value
        for constant in t.constants:
            if constant.name == value:
                return float(constant.value) if constant.type.startswith("float") else int(constant.value, 0)
        raise KeyError(f"{value} is not a constant of {message}")

    def size_of(self, message: str, path: str, value) -> int:
        t = self.type_of(message)
        view = self.defs.edition(self.defs.editions[0])
        field = next(f for f in view[t.full].fields if f.name == path)
        out = bytearray()
        codec._value(view, field.type, value, path, out)
        return len(out)

    def example(self, message: str, edition: str) -> dict:
        t = self.type_of(message)
        return default_fields(self.defs.edition(edition), t.full, default)

    def origin(self, parsed: Parsed) -> tuple | None:
        return None

    def destination(self, parsed: Parsed) -> tuple | None:
        return None

    def present(self, item) -> dict:
        out = {"message": item.message} if item.message else {}
        if item.decoded is not None:
            out["fields"] = item.decoded.get("fields", {})
        elif isinstance(item.data, dict) and "fields" in item.data:
            out["fields"] = item.data["fields"]
        return out
