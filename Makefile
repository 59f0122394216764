# Two commands do all setup on a fresh machine (Python 3.11+ and network access to PyPI):
#   make conformance   run the suite against imcpy (DUNE's C++ codec) with the defaults
#   make test          run the project's own tests (against imcpy and pyimclsts too)
# make docs builds the manual (docs/, mkdocs.yml) with --strict into site/ and serves it on http://127.0.0.1:8000.
VENV ?= .venv
PYTHON ?= python3

$(VENV)/.installed: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(VENV)/bin/python -m pip install --quiet --disable-pip-version-check -e '.[test]'
	touch $@

.PHONY: conformance test docs reference dist screenshot generate benchmark dune dune-conformance dune-record matrix mutants cpp-adapters relay dune-relay
conformance: $(VENV)/.installed
	$(VENV)/bin/imc-conformance run --adapter imcpy --json reports/imcpy.json --html reports/imcpy.html

test: $(VENV)/.installed
	$(VENV)/bin/python -m pytest -n auto --maxprocesses 4

# The manual: built with --strict (a broken link or reference stops it), its reference pages generated from the
# argument parsers and the corpus data (docs/tools/hooks.py), then served until Ctrl-C. The tests build it too
# (into a temporary folder), run its runnable examples and open it in Chromium (tests/test_docs.py).
docs: $(VENV)/.installed
	NO_MKDOCS_2_WARNING=1 $(VENV)/bin/mkdocs build --strict --site-dir site
	NO_MKDOCS_2_WARNING=1 $(VENV)/bin/mkdocs serve --strict --dev-addr 127.0.0.1:8000

# The reference pages' generated parts (command line, adapter contract, schemas, errata, coverage tables), written
# into docs/reference so that a forge shows them as the site does; tests/test_docs.py fails when one is stale.
reference: $(VENV)/.installed
	$(VENV)/bin/python docs/tools/reference.py

# The wheel and the sdist users install (pip install dist/imc_conformance-*.whl), checked with twine as the release
# workflow (.github/workflows/release.yml) publishes them.
dist: $(VENV)/.installed
	rm -rf dist
	$(VENV)/bin/python -m build --quiet --outdir dist .
	$(VENV)/bin/python -m twine check --strict dist/*

# The screenshot of the HTML report the README and the manual show (Debian's chromium), taken again.
screenshot: $(VENV)/.installed
	$(VENV)/bin/python docs/tools/screenshot.py docs/images/html-report.png

generate: $(VENV)/.installed
	$(VENV)/bin/imc-conformance generate

# Every implementation the project installs side by side (a failing run is a column, not an error), with the DUNE
# recording in tests/data judged as a capture; then the suite's power (the seeded bugs caught by corpus and fuzzer).
MATRIX = reports/matrix
matrix: $(VENV)/.installed
	mkdir -p $(MATRIX)
	for a in imcpy pyimclsts imcpy-shim pyimclsts-shim dune-cpp; do \
	  $(VENV)/bin/imc-conformance run --adapter $$a --no-progress --json $(MATRIX)/$$a.json > /dev/null; done; true
	for a in rosbags genpy roscpp; do \
	  $(VENV)/bin/imc-conformance run --suite ros_acomms --adapter $$a --no-progress --json $(MATRIX)/$$a.json > /dev/null; done; true
	$(VENV)/bin/imc-conformance pcap tests/data/dune-seed.pcapng --json $(MATRIX)/dune-recording.json > /dev/null; true
	$(VENV)/bin/imc-conformance matrix imcpy=$(MATRIX)/imcpy.json pyimclsts=$(MATRIX)/pyimclsts.json \
	  imcpy-shim=$(MATRIX)/imcpy-shim.json pyimclsts-shim=$(MATRIX)/pyimclsts-shim.json dune-cpp=$(MATRIX)/dune-cpp.json \
	  "DUNE (recording)=$(MATRIX)/dune-recording.json" rosbags=$(MATRIX)/rosbags.json genpy=$(MATRIX)/genpy.json \
	  roscpp=$(MATRIX)/roscpp.json \
	  --markdown reports/matrix.md --html reports/matrix.html

mutants: $(VENV)/.installed
	$(VENV)/bin/imc-conformance mutants
	$(VENV)/bin/imc-conformance mutants --suite ros_acomms

benchmark: $(VENV)/.installed
	$(VENV)/bin/python -m imc_conformance.benchmark

# The compiled implementations (adapters/cpp): DUNE's IMC codec and roscpp's serialization, built into the cache
# (about a minute on 2 cores the first time; the run builds them too when they are missing), then judged.
cpp-adapters: $(VENV)/.installed
	$(VENV)/bin/imc-conformance run --adapter dune-cpp --json reports/dune-cpp.json
	$(VENV)/bin/imc-conformance run --suite ros_acomms --adapter roscpp --json reports/roscpp.json; test $$? -le 1

# Two implementations judged through the relay on loopback: the reference node (serve) as the vehicle, the suite's own
# session (run, the scenarios of three queries) as the console; over a clean link, then over one losing 30% of the
# datagrams each way with a 2 s delay (seed 1). The relay's reports: reports/relay-clean.* and reports/relay-lossy.*.
RELAY_RUN = --message AcousticSystemsQuery --message LblConfig --message HistoricDataQuery --no-progress
relay: $(VENV)/.installed
	mkdir -p reports
	for link in clean: lossy:loss=0.3,delay=2; do name=$${link%%:*}; \
	  $(VENV)/bin/imc-conformance serve --port 26002 2> reports/relay-$$name-vehicle.log & vehicle=$$!; \
	  $(VENV)/bin/imc-conformance relay udp://127.0.0.1:26010 --vehicle udp://127.0.0.1:26002 --impair "$${link#*:}" \
	    --seed 1 --duration 900 --pcap reports/relay-$$name.pcapng --json reports/relay-$$name.json \
	    --html reports/relay-$$name.html > reports/relay-$$name.txt & relay=$$!; \
	  sleep 2; $(VENV)/bin/imc-conformance run --target udp://127.0.0.1:26010 $(RELAY_RUN) \
	    --json reports/relay-$$name-console.json > /dev/null; \
	  sleep 3; kill -TERM $$relay; wait $$relay; kill -TERM $$vehicle; wait $$vehicle; \
	  grep "cases in" reports/relay-$$name.txt; done

# DUNE (LSTS's IMC node) as a live target: built once from the imcpy sdist into the cache (10-30 min on 2 cores),
# then the scenario set against it inside a private network namespace (needs root for unshare --net), then live
# fuzzing (40 mutated frames a message; --fuzz-budget N to change it). Never in CI.
dune: $(VENV)/.installed
	$(VENV)/bin/python -m imc_conformance.suites.imc.dune build

dune-conformance: dune
	$(VENV)/bin/python -m imc_conformance.suites.imc.dune conformance

# DUNE against DUNE through the relay in a private network namespace: DUNE's lauv-simulator-1 configuration as two
# systems of their own (lauv-xplore-3 the vehicle, lauv-xplore-2 the console), a minute over a clean link and a minute
# losing 30% of the datagrams each way with a 2 s delay; then the same two links with the suite's own session (its
# HistoricDataQuery scenarios), then an imcpy actor, as the console (reports/dune-relay-[session-|imcpy-]{clean,impaired}.*).
# Never in CI.
dune-relay: dune
	$(VENV)/bin/python -m imc_conformance.suites.imc.dune relay

# DUNE's own traffic for a minute (every message lauv-simulator-1 transports), recorded in its namespace, then judged
# message by message with the whole protocol; and the mission log DUNE wrote meanwhile, judged with the IMC.xml
# beside it. Never in CI.
dune-record: dune
	rm -rf reports/dune-log
	$(VENV)/bin/python -m imc_conformance.suites.imc.dune record --seconds 60 --out reports/dune-whole.pcap --log-out reports/dune-log
	-$(VENV)/bin/imc-conformance pcap reports/dune-whole.pcap --suite imc-full --json reports/dune-whole.json --html reports/dune-whole.html
	$(VENV)/bin/imc-conformance log reports/dune-log/*/*/Data.lsf.gz --json reports/dune-log.json --html reports/dune-log.html

