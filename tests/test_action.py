"""The GitHub Action's run step (.ci/action.sh run): its inputs become the arguments of imc-conformance run, every
line of `args` included, never through a shell."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ACTION = Path(__file__).resolve().parent.parent / ".ci" / "action.sh"


def run_step(tmp_path: Path, args: str, require: str = "") -> tuple[subprocess.CompletedProcess, list[str] | None]:
    """The run step with ``args`` (and ``require``) as its inputs, imc-conformance replaced by a program that records its argv."""
    seen = tmp_path / "argv.json"
    fake = tmp_path / "imc-conformance"
    fake.write_text(f"#!{sys.executable}\nimport json, sys\nopen({str(seen)!r}, 'w').write(json.dumps(sys.argv[1:]))\n")
    fake.chmod(0o755)
    env = {"PATH": os.environ.get("PATH", ""), "IMC_CONFORMANCE": str(fake), "IMC_ADAPTER": "imcpy",
           "IMC_ARGS": args, "IMC_JSON": str(tmp_path / "c.json"), "IMC_JUNIT": str(tmp_path / "c.xml"),
           "IMC_HTML": str(tmp_path / "c.html"), "GITHUB_OUTPUT": str(tmp_path / "output"), "IMC_REQUIRE": require}
    done = subprocess.run(["bash", str(ACTION), "run"], env=env, cwd=tmp_path, capture_output=True, text=True,
                          timeout=60)
    return done, json.loads(seen.read_text()) if seen.exists() else None


@pytest.mark.parametrize("args", [
    "--edition imc-5.4.11\n--strict\n--message Heartbeat\n",  # a YAML block (`args: |`), one option a line
    "  --edition\timc-5.4.11 \r\n--strict   --message\n\nHeartbeat",  # blanks, tabs, CRLF and empty lines alike
])
def test_args_are_split_on_every_whitespace_newlines_included(tmp_path, args):
    done, argv = run_step(tmp_path, args)
    assert done.returncode == 0, done.stderr
    assert argv[argv.index("--adapter") + 1:argv.index("--json")] == [
        "imcpy", "--edition", "imc-5.4.11", "--strict", "--message", "Heartbeat"]
    assert (tmp_path / "output").read_text() == "exit-code=0\n"


@pytest.mark.parametrize("args", ['--claims "my claims.json"', "--id 'imc/Heartbeat/*'", "--claims my\\ claims.json"])
def test_args_a_shell_would_group_are_refused_with_a_message(tmp_path, args):
    done, argv = run_step(tmp_path, args)
    assert done.returncode == 2 and argv is None
    assert "split on whitespace" in done.stderr and "never by a shell" in done.stderr
    assert (tmp_path / "output").read_text() == "exit-code=2\n"


def test_require_is_split_as_args_are_every_line_of_a_block_required(tmp_path):
    """A message on the second line of a YAML block (`require: |`) is required too, not dropped from the gate."""
    done, argv = run_step(tmp_path, "", require="LblRange Heartbeat\n\tAnnounce\r\n")
    assert done.returncode == 0, done.stderr
    assert argv[argv.index("--adapter") + 2:argv.index("--json")] == [
        "--require", "LblRange", "--require", "Heartbeat", "--require", "Announce"]
