"""Verdicts, their severity, and the one definition of a failing verdict."""

from __future__ import annotations

from enum import Enum


class Verdict(str, Enum):
    PASS = "PASS"
    FAIL = "FAIL"
    NON_STRICT = "NON_STRICT"  # right outcome, wrong reason (e.g. the rejection named another rule)
    IMPL_DEFINED = "IMPL_DEFINED"  # an acceptable case: recorded with what the implementation did
    UNSUPPORTED = "UNSUPPORTED"  # the implementation does not do this (or, for a scenario, does not claim the service)
    INCONCLUSIVE = "INCONCLUSIVE"  # could not be tested (a parameter, a silent target): never a pass, never a fail
    CRASH = "CRASH"
    TIMEOUT = "TIMEOUT"
    ADAPTER_ERROR = "ADAPTER_ERROR"
    WAIVED = "WAIVED"  # a failure a waiver covers
    WAIVER_STALE = "WAIVER_STALE"  # a waived case that now passes: the waiver must go


# A group fails if any case has one of these; NON_STRICT and INCONCLUSIVE join them under --strict.
FAILING = (Verdict.FAIL, Verdict.CRASH, Verdict.TIMEOUT, Verdict.WAIVER_STALE, Verdict.ADAPTER_ERROR)

SEVERITY = {v: rank for rank, v in enumerate([
    Verdict.CRASH, Verdict.TIMEOUT, Verdict.ADAPTER_ERROR, Verdict.FAIL, Verdict.NON_STRICT,
    Verdict.INCONCLUSIVE, Verdict.IMPL_DEFINED, Verdict.UNSUPPORTED, Verdict.PASS])}
UNTESTED = (Verdict.INCONCLUSIVE, Verdict.UNSUPPORTED)  # verdicts that say nothing was tested
# The cases a reader must look at (reports detail them) and a rerun of what did not pass (--last-failed) runs again:
# every failing verdict, and NON_STRICT and INCONCLUSIVE even when they do not fail the run.
ATTENTION = (*FAILING, Verdict.NON_STRICT, Verdict.INCONCLUSIVE)


def failing(verdict: Verdict, strict: bool) -> bool:
    """The one definition of a failing verdict: FAILING, and NON_STRICT or INCONCLUSIVE under --strict."""
    return verdict in FAILING or (strict and verdict in (Verdict.NON_STRICT, Verdict.INCONCLUSIVE))


def worst(verdicts) -> Verdict:
    """The most severe of ``verdicts`` (UNSUPPORTED if there are none): a case's verdict from its checks'."""
    return min(verdicts, key=SEVERITY.__getitem__, default=Verdict.UNSUPPORTED)
