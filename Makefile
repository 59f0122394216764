# Two commands do all setup on a fresh machine (Python 3.11+ and network access to PyPI):
#   make conformance   run the suite against imcpy (DUNE's C++ codec) with the defaults
#   make test          run the project's own tests (against imcpy and pyimclsts too)
VENV ?= .venv
PYTHON ?= python3

$(VENV)/.installed: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(VENV)/bin/python -m pip install --quiet --disable-pip-version-check -e '.[test]'
	touch $@

.PHONY: conformance test generate benchmark dune dune-conformance
conformance: $(VENV)/.installed
	$(VENV)/bin/imc-conformance run --adapter imcpy --json reports/imcpy.json --html reports/imcpy.html

test: $(VENV)/.installed
	$(VENV)/bin/python -m pytest

generate: $(VENV)/.installed
	$(VENV)/bin/imc-conformance generate

benchmark: $(VENV)/.installed
	$(VENV)/bin/python -m imc_conformance.benchmark

# DUNE (LSTS's IMC node) as a live target: built once from the imcpy sdist into the cache (10-30 min on 2 cores),
# then the scenario set against it inside a private network namespace (needs root for unshare --net). Never in CI.
dune: $(VENV)/.installed
	$(VENV)/bin/python -m imc_conformance.suites.imc.dune build

dune-conformance: dune
	$(VENV)/bin/python -m imc_conformance.suites.imc.dune conformance

