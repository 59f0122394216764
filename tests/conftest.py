"""Shared fixtures: the definitions, the corpus, and the real implementations' adapters."""

from __future__ import annotations

import pytest

from imc_conformance.corpus_data import load_cases
from imc_conformance.definitions import load_definitions


@pytest.fixture(scope="session")
def defs():
    return load_definitions()


@pytest.fixture(scope="session")
def cases():
    return load_cases()


@pytest.fixture(scope="session")
def imcpy_adapter():
    from imc_conformance.adapters.imcpy_adapter import adapter
    return adapter()


@pytest.fixture(scope="session")
def pyimclsts_adapter():
    from imc_conformance.adapters.pyimclsts_adapter import adapter
    return adapter()
