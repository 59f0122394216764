"""The fuzz properties as ordinary hypothesis tests, for pytest and for HypoFuzz (``hypothesis fuzz``), which runs
them across cores or machines with a shared example database: scale-out with an existing engine, no scheduler of our
own. A test module of two lines exposes them::

    from imc_conformance.fuzz.properties import fuzz_tests
    globals().update(fuzz_tests("imc", "imcpy"))

Each ``test_<group>_<property>`` draws from the suite's source, judges the case through the one runner, and fails
on a deviation no documented erratum explains (hypothesis then shrinks it, as ``imc-conformance fuzz`` does).
"""

from __future__ import annotations

from ..core.verdicts import failing
from .source import PROPERTIES


def fuzz_tests(suite_name: str, adapter: str, *, edition: str | None = None, groups=(), properties=PROPERTIES,
          arguments: dict | None = None) -> dict:
    """``test_<group>_<property>`` functions for ``adapter`` (as ``--adapter`` takes it), in-process."""
    from hypothesis import HealthCheck, given, settings

    # generated frames can be large and slow to draw; nested_given stays on (HypoFuzz refuses tests that suppress it)
    SUPPRESSED = [HealthCheck.too_slow, HealthCheck.data_too_large, HealthCheck.large_base_example,
                  HealthCheck.filter_too_much]

    from ..commands.adapters import load_library_adapter
    from ..core.cases import Case
    from ..core.runner import run_cases
    from ..files import open_corpus
    from ..sessions.library import LibrarySession

    suite, cases = open_corpus(suite_name, None, frozenset(groups) or None)
    edition = edition or suite.editions[0]
    source = suite.fuzz_source(edition, cases)
    session = LibrarySession(load_library_adapter(adapter, suite, arguments), adapter)

    def make(group: str, prop: str):
        @settings(deadline=None, suppress_health_check=SUPPRESSED)
        @given(source.inputs(group, prop))
        def test(drawn):
            case = source.case(group, prop, drawn)
            if case is None:
                return
            filed = case["id"].split("/")[1]
            result = run_cases(session, suite, [Case(case["id"], filed, "vector", case)], edition=edition,
                               adapter=adapter, evidence=False).cases[0]
            suite.kinds["vector"].forget(case, edition)
            assert not (failing(result.verdict, strict=False) and not result.errata), \
                f"{result.id} {result.verdict.value}: {result.detail}\ncase: {case}"
        test.__name__ = f"test_{group}_{prop}"
        return test

    return {f"test_{g}_{p}": make(g, p) for g in source.groups if not groups or g in groups for p in properties}
