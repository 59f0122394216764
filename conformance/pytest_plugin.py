"""pytest plugin: ``pytest --conformance-adapter=SPEC`` collects the corpus as tests with the corpus's ids.

SPEC is what ``imc-conformance run --adapter`` takes (``imcpy``, ``module:attribute``, ``file.py:attribute``).
FAIL, CRASH, TIMEOUT and ADAPTER_ERROR fail the test; UNSUPPORTED skips it; IMPL_DEFINED passes and
records what the implementation did; NON_STRICT passes unless ``--conformance-strict``.
"""

from __future__ import annotations

import pytest

from .corpus_data import load_cases, select_cases
from .definitions import load_definitions
from .evaluate import Judge, Verdict, plan, worst
from .library import ask
from .results import FAILING



def pytest_addoption(parser):
    group = parser.getgroup("imc-conformance")
    group.addoption("--conformance-adapter", metavar="SPEC", help="run the IMC corpus against this library adapter")
    group.addoption("--conformance-edition", default="imc-5.4.30", help="imc-5.4.30 (default) or imc-5.4.11")
    group.addoption("--conformance-message", action="append", default=[], metavar="ABBREV", help="only this message")
    group.addoption("--conformance-id", action="append", default=[], metavar="GLOB", help="only case ids matching")
    group.addoption("--conformance-strict", action="store_true", help="NON_STRICT verdicts fail")


class ConformanceCase(pytest.Item):
    def __init__(self, *, case: dict, **kwargs):
        super().__init__(**kwargs)
        self.case = case

    def runtest(self):
        config = self.config
        state = config.stash[_STATE]
        edition = config.getoption("conformance_edition")
        results = [state["judge"].judge(self.case, edition, r, ask(state["adapter"], "imc", self.case, r))
                   for r in plan(self.case, edition, state["emits"])]
        verdict = worst(results) if results else Verdict.UNSUPPORTED
        self.user_properties.append(("verdict", verdict.value))
        detail = "; ".join(f"{r.check}: {r.verdict.value} {r.detail}" for r in results if r.verdict == verdict)
        if verdict is Verdict.UNSUPPORTED:
            pytest.skip(detail or "no check applies to this implementation")
        if verdict in FAILING or (verdict is Verdict.NON_STRICT and config.getoption("conformance_strict")):
            raise ConformanceFailure(f"{verdict.value}: {detail}")

    def repr_failure(self, excinfo):
        if isinstance(excinfo.value, ConformanceFailure):
            return f"{self.case['id']} ({self.case['clause']}): {excinfo.value}"
        return super().repr_failure(excinfo)

    def reportinfo(self):
        return self.path, None, self.case["id"]


class ConformanceFailure(Exception):
    pass


_STATE = pytest.StashKey[dict]()


def pytest_collection_modifyitems(session, config, items):
    spec = config.getoption("conformance_adapter")
    if not spec:
        return
    from .cli import UsageError, load_library_adapter

    try:
        adapter = load_library_adapter(spec)
    except UsageError as exc:
        raise pytest.UsageError(str(exc)) from exc
    config.stash[_STATE] = {"adapter": adapter, "judge": Judge(load_definitions()),
                            "emits": set(adapter.hello().get("byte_orders", ()))}
    selected = select_cases(load_cases(), config.getoption("conformance_edition"),
                            config.getoption("conformance_message"), config.getoption("conformance_id"))
    for case in selected:
        items.append(ConformanceCase.from_parent(session, name=case["id"], case=case))
