"""The starters (adapters/starters: Python with json, Java with Jackson, Go with encoding/json, Rust with serde_json, C
with cJSON), built
once into the cache (tests/starter_builds.py): their value helpers write and read back every float class at both
widths to the bit (−0.0, NaN payloads, a signalling fp32 NaN, subnormals, fp32 digits) and hex; each passes
adapter-check; a run through each is all UNSUPPORTED, without an adapter error."""

from __future__ import annotations

import json
import os
import shlex
import struct
import subprocess
import sys

import pytest

from imc_conformance.cli import main
from imc_conformance.kinds.vector.floats import FLOAT_CLASSES, float_from_bits, same_float

from starter_builds import LANGUAGES, ToolchainMissing, built, sources

EXTRA_BITS = {4: ["7f800001", "ff800001", "3dcccccd", "40490fdb", "00000000"],  # signalling NaNs, 0.1, pi
              8: ["7ff0000000000001", "3fb999999999999a", "400921fb54442d18", "41d954fc40200000"]}


def bits_of(value, width: int) -> str:
    """The hex bits of a FLOAT_CLASSES value at ``width`` bytes."""
    if isinstance(value, str):
        number = {"nan": float("nan"), "inf": float("inf"), "-inf": float("-inf")}.get(value)
        if number is None:  # "nan:<hex>"
            return value[4:]
        value = number
    return struct.pack(">" + ("f" if width == 4 else "d"), value).hex()


def probes() -> list[dict]:
    out = []
    for width, column in ((4, 0), (8, 1)):
        wanted = [bits_of(values[column], width) for values in FLOAT_CLASSES.values()] + EXTRA_BITS[width]
        out += [{"width": width, "bits": b} for b in dict.fromkeys(wanted)]
    return out


@pytest.fixture(scope="module", params=LANGUAGES)
def starter(request) -> list[str]:
    try:
        return built(request.param)
    except ToolchainMissing as missing:
        if os.environ.get("IMC_CONFORMANCE_REQUIRE_STARTERS"):
            raise
        pytest.skip(str(missing))


def test_the_value_helpers_write_every_float_class_to_the_bit(starter):
    asked = probes() + [{"hex": "00ffAB10"}, {"hex": ""}]
    done = subprocess.run([*starter, "--values"], input="".join(json.dumps(p) + "\n" for p in asked), text=True,
                          capture_output=True, timeout=60)
    answers = [json.loads(line) for line in done.stdout.splitlines()]
    assert len(answers) == len(asked), done.stderr
    for probe, answer in zip(asked, answers):
        if "hex" in probe:
            assert answer == {"hex": probe["hex"].lower()}
            continue
        width, bits = probe["width"], int(probe["bits"], 16)
        expected = float_from_bits(bits, width)
        assert same_float(expected, answer["value"], width, nan_payload=True), (probe, answer)
        assert type(answer["value"]) is type(expected) or isinstance(expected, float) and isinstance(answer["value"], float), (probe, answer)
        assert int(answer["bits"], 16) == bits, (probe, answer)  # read back from what it wrote


def test_a_starter_passes_adapter_check(starter, capsys):
    assert main(["adapter-check", "--adapter-cmd", shlex.join(starter), "--timeout", "30"]) == 0
    out = capsys.readouterr().out
    assert "MISTAKE" not in out and "the adapter speaks the contract" in out
    assert "implements nothing yet" in out and "it exited at the end of its input" in out


def test_a_run_through_a_starter_is_all_unsupported(starter, tmp_path, capsys):
    report = tmp_path / "starter.json"
    code = main(["run", "--adapter-cmd", shlex.join(starter), "--no-progress", "--timeout", "30", "--json", str(report)])
    doc = json.loads(report.read_text())
    assert code == 2 and doc["exit_code"] == 2  # nothing tested: every case UNSUPPORTED
    assert "nothing could be tested" in capsys.readouterr().err
    assert set(doc["summary"]) == {"UNSUPPORTED"} and doc["summary"]["UNSUPPORTED"] > 4000
    assert not doc["incidents"] and not doc["causes"]


@pytest.mark.parametrize("language", LANGUAGES)
def test_the_adapter_kit_copies_a_starter_and_the_contract_out_of_the_package(language, tmp_path, capsys):
    from imc_conformance.paths import CONTRACT

    kit = tmp_path / "kit"
    assert main(["adapter-kit", language, str(kit)]) == 0
    assert (kit / "ADAPTER-CONTRACT.md").read_bytes() == CONTRACT.read_bytes()
    readme = (kit / "README.md").read_text(encoding="utf-8")
    assert "](ADAPTER-CONTRACT.md)" in readme and "../../README.md" not in readme
    assert sorted(p.relative_to(kit).as_posix() for p in kit.rglob("*") if p.is_file()) == sorted(
        [*(p.relative_to(sources(language)).as_posix() for p in sources(language).rglob("*")
           if p.is_file() and "__pycache__" not in p.parts), "ADAPTER-CONTRACT.md"])
    capsys.readouterr()
    assert main(["adapter-kit", language, str(kit)]) == 2  # never over what is there
    assert "not empty" in capsys.readouterr().err


def test_an_adapter_kit_folder_the_system_cannot_look_at_is_a_one_line_error(tmp_path, capsys):
    kit = tmp_path / ("x" * 300)  # longer than a file name may be: the folder cannot even be looked up
    assert main(["adapter-kit", "python", str(kit)]) == 2
    err = capsys.readouterr().err
    assert "cannot write the kit" in err and "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_the_python_kit_passes_adapter_check_from_its_own_folder(tmp_path, capsys):
    """What a newcomer with only the wheel does: the kit written, its starter checked where it was written."""
    from imc_conformance.paths import CONTRACT

    kit = tmp_path / "my-adapter"
    assert main(["adapter-kit", "python", str(kit)]) == 0
    capsys.readouterr()
    assert main(["adapter-check", "--adapter-cmd", shlex.join([sys.executable, str(kit / "adapter.py")])]) == 0
    out = capsys.readouterr().out
    assert "implements nothing yet" in out and f"the adapter speaks the contract ({CONTRACT})" in out
    assert CONTRACT.is_file()  # the installed contract, not a path of the checkout's
