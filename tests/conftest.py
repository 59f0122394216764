"""Shared fixtures: the IMC suite, its definitions and cases, and the real implementations' adapters."""

from __future__ import annotations

import signal
import subprocess
from pathlib import Path

import pytest

from imc_conformance.files import open_corpus

CHECKOUT = Path(__file__).resolve().parents[1]
_BEFORE = pytest.StashKey[str | None]()


def checkout_state() -> str | None:
    """What git sees changed or added in the checkout (None outside a git checkout)."""
    try:
        done = subprocess.run(["git", "status", "--porcelain", "--untracked-files=all"], cwd=CHECKOUT,
                              capture_output=True, text=True, timeout=60)
    except (OSError, subprocess.TimeoutExpired):
        return None
    return done.stdout if done.returncode == 0 else None


def pytest_sessionstart(session):
    session.config.stash[_BEFORE] = checkout_state()
    # A shell without job control starts background commands with SIGINT ignored, and every program the tests start
    # would inherit that: the Ctrl-C tests could not interrupt them. Interrupts work here as in a terminal.
    if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)


def pytest_sessionfinish(session, exitstatus):
    """Tests never write into the checkout: a run that changed it fails, naming what changed."""
    before, after = session.config.stash.get(_BEFORE, None), checkout_state()
    if before is None or after is None or after == before:
        return
    changed = sorted(set(after.splitlines()) - set(before.splitlines()))
    reporter = session.config.pluginmanager.get_plugin("terminalreporter")
    if reporter is not None:
        reporter.write_line(f"the tests wrote into the checkout: {', '.join(changed) or 'files changed back'}", red=True)
    session.exitstatus = pytest.ExitCode.TESTS_FAILED


@pytest.fixture(scope="session")
def suite():
    return open_corpus("imc")[0]


@pytest.fixture(scope="session")
def defs(suite):
    return suite.defs


@pytest.fixture(scope="session")
def cases():
    """The IMC corpus as the runner sees it (``Case``: id, group, kind, data)."""
    return open_corpus("imc")[1]


@pytest.fixture(scope="session")
def imcpy_adapter():
    from imc_conformance.adapters.imcpy_adapter import adapter
    return adapter()


@pytest.fixture(scope="session")
def pyimclsts_adapter():
    from imc_conformance.adapters.pyimclsts_adapter import adapter
    return adapter()


@pytest.fixture(scope="session")
def records(cases):
    """The IMC corpus's byte vectors, as the vector files hold them."""
    return [c.data for c in cases if c.kind == "vector"]


@pytest.fixture(scope="session")
def ros():
    """The ros_acomms suite and its cases."""
    return open_corpus("ros_acomms")


@pytest.fixture(scope="session")
def rosbags_adapter():
    from imc_conformance.adapters.rosbags_adapter import RosbagsAdapter
    return RosbagsAdapter()


@pytest.fixture(scope="session")
def genpy_adapter():
    """genpy from Debian's packages, fetched into the cache on first use (apt-get download, dpkg -x)."""
    from imc_conformance.adapters.genpy_adapter import GenpyAdapter
    return GenpyAdapter()
