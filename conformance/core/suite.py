"""What a suite brings to the core, and what a case kind must do. The core knows suites only through this.

A suite (``imc_conformance.suites.<name>``) has its data folder (``vectors/<name>``: definitions, cases,
rules, errata), its editions and encodings, the groups its cases are filed under (messages, types), its
case kinds (each folder of case files belongs to one kind, which plans and judges its cases), its
built-in adapters and its errata. Adding a suite adds a package; adding a kind adds a package and a
folder of case files.
"""

from __future__ import annotations

import fnmatch
from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Protocol

from .results import CheckResult, Judgement
from .session import Answer, Request


class CaseKind(Protocol):
    """Plans the requests a case needs and judges each answer; pure (no I/O). ``options``: the run's settings
    (see ``run_cases``). A kind may also have ``admit(case, options) -> str | None``: why it declines to run
    a case under these options (effects not allowed), or None."""

    name: str

    def plan(self, case: dict, edition: str, emits: set[str], options: dict) -> list[Request]: ...

    def judge(self, case: dict, edition: str, request: Request, answer: Answer) -> CheckResult | Judgement: ...


@dataclass(frozen=True)
class Group:
    """What cases are filed under and reports are organised by: ``name`` (the second segment of their ids) and
    ``key``, the suite's own short identifier for it (a message number, a qualified type name)."""

    name: str
    key: str


@dataclass(frozen=True)
class BuiltinAdapter:
    """An adapter a suite ships: a library object (``library``: ``module:attribute``) or a subprocess shim
    (``argv()`` builds its command line, fetching what it needs)."""

    name: str
    library: str | None = None
    argv: Callable[..., list[str]] | None = None  # keyword arguments: the --adapter-arg NAME=VALUE it takes
    help: str = ""
    extra: str | None = None  # the package's optional dependencies (pip extra) a library adapter needs


class Kinds(Mapping):
    """A suite's case kinds by name, each made (its package imported) when first wanted: a run of byte vectors never
    imports the live kinds. ``makers``: name -> a function making the kind."""

    def __init__(self, makers: dict[str, Callable[[], "CaseKind"]]):
        self._makers, self._made = makers, {}

    def __getitem__(self, name: str) -> "CaseKind":
        if name not in self._made:
            self._made[name] = self._makers[name]()
        return self._made[name]

    def __iter__(self):
        return iter(self._makers)

    def __len__(self) -> int:
        return len(self._makers)


class Suite(ABC):
    name: str  # the first segment of every case id
    title: str  # how reports name the suite
    editions: tuple[str, ...]  # the default first
    encodings: tuple[str, ...]  # the wire encodings a case may have frames in (byte orders, serializations)
    encoding_param: str  # how the adapter protocol names an encoding; hello lists the emitted ones as <param>s
    group_label: str  # what a group is ("message", "type")
    case_folders: dict[str, str]  # folder of case files under the data folder -> case kind name

    def __init__(self, folder: Path):
        self.folder = folder

    @property
    @abstractmethod
    def groups(self) -> tuple[Group, ...]:
        """Every group, in report order."""

    @property
    @abstractmethod
    def kinds(self) -> Mapping[str, CaseKind]:
        """The case kinds, by name (``Kinds``: each made when first wanted)."""

    @property
    @abstractmethod
    def adapters(self) -> dict[str, BuiltinAdapter]:
        """The built-in adapters, by name; the first is the default."""

    @abstractmethod
    def schema(self, kind: str) -> Path:
        """The JSON Schema of this suite's files of case kind ``kind``."""

    @abstractmethod
    def group_of(self, doc: dict) -> str:
        """The group a case file declares (every case in it is filed there)."""

    @abstractmethod
    def case_problem(self, kind: str, case: dict) -> tuple[str, str] | None:
        """(JSON path suffix, what is wrong) for a problem of a schema-valid case that only the definitions
        can see (a value that does not fit its field), or None."""

    @property
    @abstractmethod
    def errata(self) -> list[dict]:
        """The suite's errata (``id``, and for an implementation's: ``implementation`` and case globs)."""

    def implementation_errata(self, case_id: str, key: str | None, tags=()) -> list[str]:
        """Ids of the errata of implementation ``key`` that name the case: by a glob over case ids
        (``cases``), by tags the case has all of (``tags``), or by one set of tags it has all of (``tag_sets``,
        which is how generated cases are named)."""
        if key is None:
            return []
        tags = set(tags)
        return [e["id"] for e in self.errata if key in erratum_keys(e.get("implementation")) and (
            any(fnmatch.fnmatchcase(case_id, g) for g in e.get("cases", ()))
            or ("tags" in e and set(e["tags"]) <= tags)
            or any(set(s) <= tags for s in e.get("tag_sets", ())))]

    @abstractmethod
    def generate(self, check: bool) -> int:
        """Rebuild the suite's generated files (or, with ``check``, only report drift: 1 if any); the exit code."""

    # optional: generate_from(source: Path, out: Path) -> int, a suite folder built from a protocol description
    # (IMC: an IMC.xml), ValueError for one it cannot read

    behaviour: dict | None = None  # what the suite's live case kinds share (exchanges, parameters, effects, services)

    def open_target(self, target: str, **settings):
        """A session with a live target (``--target``), for the suite's scenarios; ValueError with a one-line
        reason if it cannot be opened. Settings: ``bind``, ``src``, ``dst``, ``allow_group``, ``startup``,
        ``restart`` (a function restarting the target, or None), ``recorder`` (told of every datagram, or None),
        ``first_unique`` (where the run's request ids start: random per run, recorded)."""
        raise ValueError(f"the suite {self.name!r} has no live targets")

    def capture_rules(self):
        """What the suite judges in captures (``capture.findings.CaptureRules``); ValueError if it has none."""
        raise ValueError(f"the suite {self.name!r} is not carried in datagrams: it has no captures to judge")

    def relay_hooks(self) -> dict:
        """What the relay (``relay.core.Relay``) needs of the suite, as its keyword arguments: ``rewrite(data,
        facing)``, a datagram changed so that replies come back through the relay; ``resend``, the (ambiguity, clause)
        under which a requester's resending of a lost request is recorded; ``introductions``, the messages by which a
        system makes itself known; ``reply_to(data)``, the (host, port) a datagram asks replies to be sent to (an
        announced address), or None. None of them for a suite that needs none."""
        return {}

    def log_reader(self, edition: str | None = None):
        """How the suite reads its mission logs (``capture.logs.LogReader``), judging in ``edition`` (None: the
        reader's choice); ValueError if it reads none."""
        raise ValueError(f"the suite {self.name!r} reads no mission logs")

    def open_replay(self, link, **settings):
        """A session replaying a recorded run over ``link`` (sessions/replay.py); settings as the run had them:
        ``target``, ``src``, ``dst``, ``startup``, ``first_unique``."""
        raise ValueError(f"the suite {self.name!r} has no live targets to replay")

    def fuzz_source(self, edition: str, cases=()):
        """The suite's fuzz source (``fuzz.source.FuzzSource``) for ``edition``; ``cases``: the loaded corpus, whose
        valid frames the fast mutation engine starts from. ValueError if the suite has none."""
        raise ValueError(f"the suite {self.name!r} has no fuzz source")

    def mutants(self, edition: str | None = None) -> list:
        """The suite's seeded-bug implementations (``fuzz.mutation.Mutant``) for ``edition``, for ``imc-conformance
        mutants``."""
        return []

    def profile(self, name: str) -> dict:
        """The profile ``name`` of the suite's scenarios (``profiles/<name>.json``); ValueError if unknown."""
        raise ValueError(f"the suite {self.name!r} has no profiles")


def erratum_keys(implementation) -> tuple[str, ...]:
    """The hello keys an erratum applies to (its ``implementation``: one key or a list of them)."""
    if implementation is None:
        return ()
    return (implementation,) if isinstance(implementation, str) else tuple(implementation)
