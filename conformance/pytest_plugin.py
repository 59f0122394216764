"""pytest plugin: ``pytest --conformance-adapter=SPEC`` collects a suite's corpus as tests with the corpus's ids.

SPEC is what ``imc-conformance run --adapter`` takes (a built-in name, ``module:attribute``,
``file.py:attribute``). The selected cases run through the same runner as the command line, once, when
the first of them runs; each test then reports its case: a failing verdict (FAIL, CRASH, TIMEOUT,
ADAPTER_ERROR; NON_STRICT with ``--conformance-strict``) fails it, UNSUPPORTED skips it, IMPL_DEFINED
passes and records what the implementation did.
"""

from __future__ import annotations

import pytest

from .core.cases import select_cases
from .core.verdicts import Verdict, failing


def pytest_addoption(parser):
    group = parser.getgroup("imc-conformance")
    group.addoption("--conformance-adapter", metavar="SPEC", help="run a suite's corpus against this library adapter")
    group.addoption("--conformance-suite", help="the suite (default: the command line's default suite)")
    group.addoption("--conformance-edition", help="the edition (default: the suite's first)")
    group.addoption("--conformance-message", action="append", default=[], metavar="NAME", help="only this message/type")
    group.addoption("--conformance-id", action="append", default=[], metavar="GLOB", help="only case ids matching")
    group.addoption("--conformance-strict", action="store_true", help="NON_STRICT verdicts fail")


class ConformanceCase(pytest.Item):
    def __init__(self, *, case, **kwargs):
        super().__init__(**kwargs)
        self.case = case

    def runtest(self):
        state = self.config.stash[_STATE]
        if "results" not in state:
            state["results"] = run_selected(state, [i.case for i in self.session.items if isinstance(i, ConformanceCase)])
        result = state["results"].get(self.case.id)
        if result is None:  # interrupted before this case was done
            pytest.skip("the run was interrupted before this case")
        self.user_properties.append(("verdict", result.verdict.value))
        detail = f"{result.verdict.value}: {result.detail}"
        if result.verdict is Verdict.UNSUPPORTED:
            pytest.skip(detail)
        if failing(result.verdict, self.config.getoption("conformance_strict")):
            raise ConformanceFailure(detail)

    def repr_failure(self, excinfo):
        if isinstance(excinfo.value, ConformanceFailure):
            return f"{self.case.id} ({self.case.data['clause']}): {excinfo.value}"
        return super().repr_failure(excinfo)

    def reportinfo(self):
        return self.path, None, self.case.id


class ConformanceFailure(Exception):
    pass


_STATE = pytest.StashKey[dict]()


def run_selected(state: dict, cases) -> dict:
    """Case id -> CaseResult for ``cases``, run through the runner."""
    from .core.runner import run_cases
    from .sessions.calls import CallTarget
    from .sessions.library import LibrarySession

    session = CallTarget(LibrarySession(state["adapter"], state["spec"]))
    try:
        result = run_cases(session, state["suite"], cases, edition=state["edition"], adapter=state["spec"],
                           strict=state["strict"], corpus=state["corpus"])
    finally:
        session.close()
    return {c.id: c for c in result.cases}


def pytest_collection_modifyitems(session, config, items):
    spec = config.getoption("conformance_adapter")
    if not spec:
        return
    from .commands.adapters import load_library_adapter
    from .errors import CorpusError, UsageError
    from .files import open_corpus
    from .suites import names

    try:
        suite, everything = open_corpus(config.getoption("conformance_suite") or names()[0])
        adapter = load_library_adapter(spec, suite)
    except (UsageError, CorpusError) as exc:
        raise pytest.UsageError(str(exc)) from exc
    edition = config.getoption("conformance_edition") or suite.editions[0]
    if edition not in suite.editions:
        raise pytest.UsageError(f"unknown edition {edition!r} of the suite {suite.name!r}")
    config.stash[_STATE] = {"adapter": adapter, "spec": spec, "suite": suite, "edition": edition,
                            "strict": config.getoption("conformance_strict"), "corpus": everything}
    for case in select_cases(everything, edition, config.getoption("conformance_message"),
                             config.getoption("conformance_id")):
        items.append(ConformanceCase.from_parent(session, name=case.id, case=case))
