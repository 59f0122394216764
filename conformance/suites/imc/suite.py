"""The IMC suite as the core sees it: its data folder, editions, byte orders, messages, codec, adapters."""

from __future__ import annotations

import importlib
import sys
from functools import cached_property, lru_cache
from pathlib import Path

from ...core.suite import BuiltinAdapter, Group, Kinds
from ...paths import VECTORS
from . import codec
from .compare import Comparator
from .decoded_form import message_problem
from .values import text_bytes
from ...kinds.vector.texts import lossy_bytes
from .definitions import Definitions, load_definitions, parse_definitions
from ..data_suite import DataSuite, read_data_file
from .paths import IMC

ADAPTERS_PACKAGE = "imc_conformance.adapters"


class ImcCodec:
    """The IMC reference codec and decoded-form policy, as the vector kind needs them."""

    encodings = ("le", "be")

    def __init__(self, defs: Definitions, rules: frozenset[str]):
        self.defs, self.rules = defs, rules
        self.comparator = Comparator(defs)

    def encode(self, message: dict, encoding: str, edition: str) -> bytes:
        return codec.encode(self.defs, message, encoding)

    def layout(self, frame: bytes, encoding: str, case: dict, edition: str) -> list:
        return codec.layout(self.defs, frame)

    def differences(self, expected: dict, actual, nan_payload: bool, edition: str) -> list:
        return self.comparator.messages(expected, actual, nan_payload=nan_payload)

    def malformed(self, message, case: dict, edition: str) -> str | None:
        problem = message_problem(self.defs, message, whole_header=True, in_range=False)
        return None if problem is None else f"malformed answer: message{problem[0]}: {problem[1]}"

    def params(self, case: dict, op: str, encoding: str | None) -> dict:
        return {}  # an IMC frame names its message and byte order itself

    def describe_differences(self, expected: dict, actual, case: dict, edition: str) -> list[str]:
        return ["IMC vectors have no describe check"]

    def decode(self, frame: bytes, encoding: str, case: dict, edition: str) -> dict:
        return codec.decode(self.defs, frame)

    def tolerates(self, outcome: str, op: str, difference) -> bool:
        """restamp (encoding): another header timestamp; lossy (decoding): plaintext with its non-ASCII bytes replaced
        (texts.lossy_bytes, on the bytes the answer stands for, string or {"hex"}). A roundtrip both decodes and
        encodes."""
        if outcome == "restamp" and op != "decode":
            return difference.path == "header.timestamp"
        if outcome == "lossy" and op != "encode" and difference.why == "plaintext":
            try:
                return lossy_bytes(text_bytes(difference.expected), text_bytes(difference.actual))
            except ValueError:
                return False
        return False


class ImcSuite(DataSuite):
    name = "imc"
    title = "IMC"
    encodings = ImcCodec.encodings
    encoding_param = "byte_order"
    group_label = "message"
    case_folders = {"cases": "vector", "scenarios": "scenario", "robustness": "robustness"}
    packaged = IMC
    data_schemas = {"definitions.json": "definitions.schema.json", "rules.json": "rules.schema.json",
                    "exchanges.json": "exchanges.schema.json", "statements.json": "statements.schema.json",
                    "errata.json": "errata.schema.json", "ambiguities.json": "ambiguities.schema.json"}

    def __init__(self, folder: Path, defs: Definitions, packaged: Path = IMC, title: str = "IMC"):
        super().__init__(folder)
        self.defs, self.packaged, self.title = defs, packaged, title
        # the newest first: what imcpy and deployed DUNE speak (5.4.30) before the seeds' (5.4.11)
        self.editions = tuple(sorted(defs.editions, key=lambda e: tuple(map(int, e[4:].split("."))), reverse=True))

    @cached_property
    def groups(self) -> tuple[Group, ...]:
        return tuple(Group(m.abbrev, str(m.id)) for m in self.defs.suite_messages)

    @cached_property
    def kinds(self) -> Kinds:
        return Kinds({"vector": self._vector_kind, "scenario": self._scenario_kind, "robustness": self._robustness_kind})

    def _vector_kind(self):
        from ...kinds.vector import VectorKind  # each kind is imported when a run plans its cases

        return VectorKind(ImcCodec(self.defs, frozenset(r["id"] for r in self.rules)))

    def _scenario_kind(self):
        from ...kinds.scenario import ScenarioKind

        return ScenarioKind(self.wire, self.behaviour)

    def _robustness_kind(self):
        from ...kinds.robustness import RobustnessKind

        return RobustnessKind(self.wire, self.behaviour)

    @cached_property
    def wire(self):
        from .wire import ImcWire

        return ImcWire(self.defs, {r["id"]: r["clause"] for r in self.rules})

    @property
    def adapters(self) -> dict[str, BuiltinAdapter]:
        return {
            "imcpy": BuiltinAdapter("imcpy", library=f"{ADAPTERS_PACKAGE}.imcpy_adapter:adapter",
                                    extra="imcpy", help="imcpy, DUNE's C++ codec (library)"),
            "pyimclsts": BuiltinAdapter("pyimclsts", library=f"{ADAPTERS_PACKAGE}.pyimclsts_adapter:adapter",
                                        extra="pyimclsts", help="pyimclsts (library)"),
            "imcpy-shim": BuiltinAdapter("imcpy-shim", argv=lambda: shim_argv("imcpy_shim.py") + [
                "--definitions", str(self.packaged / "definitions.json")], help="imcpy through the subprocess protocol"),
            "pyimclsts-shim": BuiltinAdapter("pyimclsts-shim", argv=pyimclsts_shim_argv,
                                             help="pyimclsts through the subprocess protocol"),
            "dune-cpp": BuiltinAdapter("dune-cpp", argv=lambda: dune_cpp_argv(self.packaged / "definitions.json"),
                                       help="DUNE's IMC codec in C++, without the binding (subprocess; built on first use)"),
        }

    def schema(self, kind: str) -> Path:
        return VECTORS / "schema" / {"scenario": "scenarios.schema.json", "robustness": "robustness.schema.json"}.get(
            kind, "vectors.schema.json")

    @staticmethod
    def group_of(doc: dict) -> str:
        return doc["message"]["abbrev"]

    def case_problem(self, kind: str, case: dict) -> tuple[str, str] | None:
        """The first problem of the case against the definitions: a definition it was built for that they do not
        give, then its message (a decoded form needs its whole header); for a scenario, of its steps against the
        definitions and the exchange rules."""
        if kind in ("scenario", "robustness"):
            return self.live_problem(kind, case)
        for abbrev, built in case.get("definitions", {}).items():  # a changed definition invalidates its cases
            mdef = self.defs.by_abbrev.get(abbrev)
            if mdef is None or mdef.hash != built:
                return f".definitions.{abbrev}", (f"built for another definition of {abbrev} ({built}, where the "
                                                  f"definitions give {mdef.hash if mdef else 'none'}): generate the "
                                                  "case files again")
        if "message" not in case:
            return None
        expects = {case["expect"]} if isinstance(case["expect"], str) else set(case["expect"].values())
        decoded = expects & {"valid", "acceptable"} and any(c.startswith(("decode", "roundtrip")) for c in case["checks"])
        problem = message_problem(self.defs, case["message"], whole_header=bool(decoded), in_range=True)
        return None if problem is None else (".message" + problem[0], problem[1])

    def generate(self, check: bool) -> int:
        from .corpus.build import main
        return main(["--check"] if check else [])

    def generate_from(self, source: Path, out: Path) -> int:
        """A suite folder for the IMC.xml ``source``, written into ``out``; ValueError for an XML it cannot read."""
        from .xml_folder import folder_from_xml
        return folder_from_xml(source, out)

    def fuzz_source(self, edition: str, cases=()):
        from ...fuzz.source import valid_frames
        from .fuzzing import ImcFuzzSource

        return ImcFuzzSource(self.defs, edition, {r["id"]: r["clause"] for r in self.rules}, valid_frames(cases, edition))

    def mutants(self, edition: str | None = None) -> list:
        from ...fuzz.mutation import Mutant
        from . import mutants

        return [Mutant(m.name, m.__doc__, lambda m=m: m(self.defs), getattr(m, "equivalent", None), m in mutants.NEW)
                for m in mutants.MUTANTS]

    def capture_rules(self):
        from .capture import ImcCaptureRules
        return ImcCaptureRules(self.defs, self.wire, self.rules, self.behaviour)

    @staticmethod
    @lru_cache(maxsize=4)
    def over_xml(raw: bytes) -> ImcSuite:
        """The IMC suite over the definitions of another IMC.xml (a log's own: every message it defines; the rules,
        exchanges and clauses of the packaged suite); ValueError (XmlError) naming what it cannot read. One object
        per XML's bytes."""
        from .from_xml import xml_document

        defs = parse_definitions(xml_document(raw))
        return ImcSuite(IMC, defs, title=f"IMC {defs.editions[0][4:]} (the log's IMC.xml)")

    def relay_hooks(self) -> dict:
        from .relay import INTRODUCTIONS, RESEND, AnnounceRewriter
        rewriter = AnnounceRewriter(self.defs)
        return {"rewrite": rewriter, "reply_to": rewriter.reply_to, "resend": RESEND, "introductions": INTRODUCTIONS}

    def log_reader(self, edition: str | None = None):
        from .lsf import LsfReader
        return LsfReader(self, edition)

    def open_target(self, target: str, **settings):
        from .live import open_target
        return open_target(self, target, **settings)

    def open_replay(self, link, **settings):
        from .live import open_replay
        return open_replay(self, link, **settings)


def shim_argv(script: str) -> list[str]:
    """The command line of one of the subprocess shims shipped in ``adapters/``."""
    folder = Path(importlib.import_module(ADAPTERS_PACKAGE).__file__).parent
    return [sys.executable, str(folder / script)]


def pyimclsts_shim_argv() -> list[str]:
    from ...cache import cache_dir
    from .imc_xml import fetch_imc_xml

    return shim_argv("pyimclsts_shim.py") + ["--imc-xml", str(fetch_imc_xml()), "--cache",
                                             str(cache_dir() / "pyimclsts-shim")]


def dune_cpp_argv(definitions: Path) -> list[str]:
    from .dune.codec import argv

    return argv(definitions)


def load(folder: Path | None = None) -> ImcSuite:
    """The IMC suite over its packaged data, or over a suite folder given instead (its definitions.json, if
    it has one, replace the packaged definitions)."""
    folder = Path(folder) if folder is not None else IMC
    own = folder / "definitions.json"
    if not own.exists() or own.is_relative_to(IMC):
        return ImcSuite(folder, load_definitions())
    doc = read_data_file(own, ImcSuite.data_schemas["definitions.json"], IMC)
    return ImcSuite(folder, parse_definitions(doc))


def load_whole(folder: Path) -> ImcSuite:
    """The IMC suite over a whole-protocol folder (``whole.whole_folder``): its files are trusted by its own
    manifest, as the packaged folder's are."""
    defs = parse_definitions(read_data_file(folder / "definitions.json", ImcSuite.data_schemas["definitions.json"], folder))
    return ImcSuite(folder, defs, packaged=folder, title="IMC (whole protocol)")
