# Two commands do all setup on a fresh machine (Python 3.11+ and network access to PyPI):
#   make conformance   run the suite against imcpy (DUNE's C++ codec) with the defaults
#   make test          run the project's own tests (against imcpy and pyimclsts too)
VENV ?= .venv
PYTHON ?= python3

$(VENV)/.installed: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(VENV)/bin/python -m pip install --quiet --disable-pip-version-check -e '.[test]'
	touch $@

.PHONY: conformance test generate benchmark
conformance: $(VENV)/.installed
	$(VENV)/bin/imc-conformance run --adapter imcpy --json reports/imcpy.json --html reports/imcpy.html

test: $(VENV)/.installed
	$(VENV)/bin/python -m pytest

generate: $(VENV)/.installed
	$(VENV)/bin/imc-conformance generate

benchmark: $(VENV)/.installed
	$(VENV)/bin/python -m imc_conformance.benchmark
