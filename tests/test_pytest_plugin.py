"""The pytest plugin collects the corpus as tests with the corpus's ids and judges them like the runner.

Runs that load imcpy use a pytest subprocess: its pybind11 module cannot be imported twice in one process.
"""

from __future__ import annotations

import json

pytest_plugins = ["pytester"]

BROKEN_ADAPTER = '''

from imc_conformance.suites.imc import codec
from imc_conformance.adapter_api import Rejected
from imc_conformance.suites.imc.definitions import load_definitions

DEFS = load_definitions()


class IgnoresCrc:
    """The reference codec, except that it never checks the CRC."""

    def hello(self):
        return {"implementation": "ignores-crc", "suites": ["imc"], "byte_orders": ["le", "be"]}

    def encode(self, suite, message, byte_order):
        return codec.encode(DEFS, message, byte_order)

    def decode(self, suite, frame):
        try:
            return codec.decode(DEFS, frame, off=frozenset({"crc"}))
        except codec.FrameError as exc:
            raise Rejected(exc.detail, exc.rule) from exc


adapter = IgnoresCrc()
'''


def test_cases_become_tests_with_the_corpus_ids(pytester):
    from imc_conformance.suites.imc.paths import imc_data
    lblrange = json.loads(imc_data("cases", "200-LblRange.json").read_text(encoding="utf-8"))["cases"]
    result = pytester.runpytest_subprocess("--conformance-adapter=imcpy", "--conformance-message=LblRange", "-v")
    result.assert_outcomes(passed=len(lblrange))
    result.stdout.fnmatch_lines(["*imc/LblRange/boundary/range/negative-zero PASSED*",
                                 "*imc/LblRange/crc/footer-first-byte/be PASSED*"])


def test_failures_name_the_case_clause_and_detail(pytester):
    result = pytester.runpytest_subprocess("--conformance-adapter=pyimclsts", "--conformance-id=imc/LblRange/crc/*",
                                           "--conformance-id=imc/LblRange/minimal")
    result.assert_outcomes(passed=1, failed=18)  # pyimclsts checks no CRC (erratum P1)
    result.stdout.fnmatch_lines(["*imc/LblRange/crc/payload/le (imc-xml#footer.crc16): FAIL: decode-le: accepted an "
                                 "invalid frame (rule crc)*"])


def test_a_broken_adapter_file_is_caught(pytester):
    pytester.makepyfile(broken_adapter=BROKEN_ADAPTER)
    result = pytester.runpytest(f"--conformance-adapter={pytester.path / 'broken_adapter.py'}:adapter",
                                "--conformance-id=imc/LblRange/crc/*", "--conformance-id=imc/LblRange/minimal")
    result.assert_outcomes(passed=1, failed=18)  # every CRC case, in both byte orders, catches it
    result.stdout.fnmatch_lines(["*imc/LblRange/crc/footer-first-byte/le (imc-xml#footer.crc16): FAIL: decode-le: "
                                 "accepted an invalid frame (rule crc)*"])


def test_nothing_is_collected_without_the_option(pytester):
    pytester.makepyfile(test_one="def test_one():\n    pass\n")
    pytester.runpytest().assert_outcomes(passed=1)


def test_an_unloadable_adapter_is_a_usage_error(pytester):
    result = pytester.runpytest("--conformance-adapter=no_such_module:adapter")
    assert result.ret == 4  # pytest's usage-error exit code
    result.stderr.fnmatch_lines(["*cannot load adapter 'no_such_module:adapter'*"])


def test_the_plugin_runs_any_suite(pytester):
    result = pytester.runpytest_subprocess("--conformance-suite=ros_acomms", "--conformance-adapter=rosbags",
                                           "--conformance-message=Packet", "-q")
    result.assert_outcomes(passed=48)
