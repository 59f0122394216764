"""The ros_acomms suite as the core sees it: its data folder, editions, the ROS 1 encoding, types, codec,
adapters, and the subcommand that writes the package's .msg and .srv files."""

from __future__ import annotations

from functools import cached_property
from pathlib import Path

from ...core.suite import BuiltinAdapter, Group, Kinds
from ...paths import VECTORS
from . import codec, forms
from ...kinds.vector.texts import lossy_bytes
from .definitions import DefinitionError, RosDefinitions, load_definitions, parse_definitions
from .msgtext import expected_types, parse_full_text, text_differences
from ..data_suite import DataSuite, read_data_file
from .paths import ROS

ADAPTERS_PACKAGE = "imc_conformance.adapters"


class RosCodec:
    """The ROS 1 reference codec and decoded-form policy, as the vector kind needs them."""

    encodings = ("ros1",)

    def __init__(self, defs: RosDefinitions, rules: frozenset[str]):
        self.defs, self.rules = defs, rules

    def encode(self, message: dict, encoding: str, edition: str) -> bytes:
        return codec.encode(self.defs.edition(edition), message, encoding)

    def layout(self, frame: bytes, encoding: str, case: dict, edition: str) -> list:
        return codec.layout(self.defs.edition(edition), case["type"], frame)

    def differences(self, expected: dict, actual, nan_payload: bool, edition: str) -> list:
        return forms.differences(self.defs.edition(edition), expected, actual, nan_payload)

    def malformed(self, message, case: dict, edition: str) -> str | None:
        problem = forms.message_problem(self.defs.edition(edition), message, strict=False, expect_type=case["type"])
        return None if problem is None else f"malformed answer: message{problem[0]}: {problem[1]}"

    def params(self, case: dict, op: str, encoding: str | None) -> dict:
        return {"type": case["type"]} if op == "describe" else {"type": case["type"], "encoding": encoding}

    def describe_differences(self, expected: dict, actual, case: dict, edition: str) -> list[str]:
        """The MD5 must be the expected one, the service's too where the answer gives it, and the definition
        text must describe the same types, constants and fields (comments and layout aside)."""
        if not isinstance(actual, dict):
            return ["no description"]
        out = [f"{key} {str(actual.get(key))[:40]!r}, expected {expected[key]}" for key in ("md5", "service_md5")
               if key in expected and (key == "md5" or key in actual) and actual.get(key) != expected[key]]
        text = actual.get("definition")
        if not isinstance(text, str):
            return out + ["no definition text"]
        view = self.defs.edition(edition)
        try:
            described = parse_full_text(text, case["type"])
        except DefinitionError as exc:
            return out + [f"the definition text does not parse: {exc}"]
        return out + text_differences(expected_types(view, view[case["type"]]), described)

    def decode(self, frame: bytes, encoding: str, case: dict, edition: str) -> dict:
        return codec.decode(self.defs.edition(edition), case["type"], frame)

    def tolerates(self, outcome: str, op: str, difference) -> bool:
        """lossy (decoding, or a roundtrip): a string whose bytes that are not UTF-8 were replaced
        (texts.lossy_bytes, on the bytes the answer stands for, string or {"hex"})."""
        if outcome == "lossy" and op != "encode" and difference.why == "string":
            try:
                return lossy_bytes(codec.string_bytes(difference.expected), codec.string_bytes(difference.actual))
            except ValueError:
                return False
        return False


class RosSuite(DataSuite):
    name = "ros_acomms"
    title = "ros_acomms_msgs"
    encodings = RosCodec.encodings
    encoding_param = "encoding"
    group_label = "type"
    case_folders = {"cases": "vector", "scenarios": "scenario"}
    packaged = ROS
    data_schemas = {"definitions.json": "ros_acomms-definitions.schema.json", "rules.json": "rules.schema.json",
                    "exchanges.json": "exchanges.schema.json", "statements.json": "statements.schema.json",
                    "errata.json": "ros_acomms-errata.schema.json"}

    def __init__(self, folder: Path, defs: RosDefinitions):
        super().__init__(folder)
        self.defs = defs
        self.editions = defs.editions

    @cached_property
    def groups(self) -> tuple[Group, ...]:
        return tuple(Group(t.name, t.full if t.kind == "msg" else f"{t.package}/{t.service} ({t.kind})")
                     for t in self.defs.suite_types)

    @cached_property
    def kinds(self) -> Kinds:
        return Kinds({"vector": self._vector_kind, "scenario": self._scenario_kind})

    def _vector_kind(self):
        from ...kinds.vector import VectorKind  # each kind is imported when a run plans its cases

        return VectorKind(RosCodec(self.defs, frozenset(r["id"] for r in self.rules)))

    def _scenario_kind(self):
        from ...kinds.scenario import ScenarioKind

        return ScenarioKind(self.wire, self.behaviour)

    @cached_property
    def wire(self):
        from .wire import RosWire

        return RosWire(self.defs)

    @property
    def adapters(self) -> dict[str, BuiltinAdapter]:
        return {
            "rosbags": BuiltinAdapter("rosbags", library=f"{ADAPTERS_PACKAGE}.rosbags_adapter:RosbagsAdapter",
                                      extra="ros", help="rosbags (library; --adapter-arg edition=E or msgs=DIR)"),
            "genpy": BuiltinAdapter("genpy", library=f"{ADAPTERS_PACKAGE}.genpy_adapter:GenpyAdapter",
                                    extra="ros", help="genpy from Debian (library; --adapter-arg edition=E or msgs=DIR)"),
            "roscpp": BuiltinAdapter("roscpp", argv=roscpp_argv,
                                     help="roscpp's serialization in C++ (subprocess, built on first use; --adapter-arg "
                                          "edition=E or msgs=DIR)"),
            "reference-handler": BuiltinAdapter("reference-handler", library=f"{__package__}.handler:ReferenceHandler",
                                                help="the suite's reference service handler (library; scenarios; "
                                                     "--adapter-arg broken=NAME breaks one rule)"),
        }

    def schema(self, kind: str) -> Path:
        return VECTORS / "schema" / ("scenarios.schema.json" if kind == "scenario" else "ros_acomms-vectors.schema.json")

    def group_of(self, doc: dict) -> str:
        return doc["message"].get("name") or doc["message"]["abbrev"]

    def case_problem(self, kind: str, case: dict) -> tuple[str, str] | None:
        """Per edition the case exists in: its type must exist, its MD5 must be the type's (a changed
        definition invalidates exactly the cases that pinned the old one), its message must fit the type. A
        scenario: what the definitions and the exchanges file can see."""
        from .msgtext import md5

        if kind == "scenario":
            return self.live_problem(kind, case)
        editions = list(self.defs.editions) if isinstance(case["expect"], str) else list(case["expect"])
        for name in editions:
            view = self.defs.edition(name)
            if case["type"] not in view:
                return ".type", f"{case['type']} is not a type of edition {name}"
            if case["md5"] != md5(view, view[case["type"]]):
                return ".md5", f"{case['md5']} is not the MD5 of {case['type']} in edition {name}: the definition changed"
            if "message" in case:  # an input only an encoder is given may hold what its field cannot carry
                decoded = any(check.startswith(("decode", "roundtrip")) for check in case["checks"])
                problem = forms.message_problem(view, case["message"], strict=True, in_range=decoded)
                if problem:
                    return ".message" + problem[0], f"{problem[1]} (edition {name})"
        return None

    def fuzz_source(self, edition: str, cases=()):
        from ...fuzz.source import valid_frames
        from .fuzzing import RosFuzzSource

        return RosFuzzSource(self.defs.edition(edition), {t.name: t.full for t in self.defs.suite_types},
                             {r["id"]: r["clause"] for r in self.rules}, valid_frames(cases, edition))

    def mutants(self, edition: str | None = None) -> list:
        from ...fuzz.mutation import Mutant
        from . import mutants

        edition = edition or self.editions[0]
        return [Mutant(m.name, m.__doc__, lambda m=m: m(edition), getattr(m, "equivalent", None), m in mutants.NEW)
                for m in mutants.MUTANTS]

    def log_reader(self, edition: str | None = None):
        from .bags import BagReader
        return BagReader(self, edition)

    def generate(self, check: bool) -> int:
        from .corpus.build import main
        return main(["--check"] if check else [])


def load(folder: Path | None = None) -> RosSuite:
    """The ros_acomms suite over its packaged data, or over a suite folder given instead."""
    folder = Path(folder) if folder is not None else ROS
    own = folder / "definitions.json"
    if not own.exists() or own.is_relative_to(ROS):
        return RosSuite(folder, load_definitions())
    doc = read_data_file(own, RosSuite.data_schemas["definitions.json"], ROS)
    try:
        return RosSuite(folder, parse_definitions(doc))
    except DefinitionError as exc:
        from ...errors import CorpusError
        raise CorpusError(f"{own}: {exc}") from None


def roscpp_argv(edition: str | None = None, msgs: str | None = None) -> list[str]:
    from .roscpp import argv

    return argv(edition, msgs)
