"""How the benchmark measures: medians of timed calls, the wheel installed for the whole-process rows, whole
commands and the bare interpreter beside them; the settings every row shares."""

from __future__ import annotations

import os
import statistics
import subprocess
import sys
import sysconfig
import tempfile
import time
from pathlib import Path


EDITION = "imc-5.4.30"
ROS_EDITION = "seed"
CAPTURE_FRAMES = 1_000_000
LIVE_PARAMS = {"peer": "imc-peer-1", "beacon": "b1", "sms_number": "+351000000000", "remote_system": 8208}
COUNTS: dict[str, int] = {}  # cases or frames of the rate rows, filled as they are measured


def timed(fn) -> float:
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def median_of(repeat: int, fn) -> float:
    return statistics.median(timed(fn) for _ in range(repeat))


INSTALLED: dict[str, str] = {}  # "python" and "script" of the virtual environment the wheel is installed in, when made


def command_env(cache: str | None = None) -> dict:
    """The environment of a measured command: bytecode cached as an install has it, a cache folder if given."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONDONTWRITEBYTECODE", "PYTHONPATH")}
    if cache is not None:
        env["IMC_CONFORMANCE_CACHE"] = cache
    return env


def install_wheel(folder: Path) -> None:
    """From a checkout: build the wheel and install it, as a user does, into a virtual environment in ``folder``
    (outside the checkout), whose ``imc-conformance`` and interpreter the whole-process rows then run. Its
    dependencies (and imcpy) are this environment's, found after its own packages (a path file), so that nothing is
    downloaded and the anchors (``python -c pass``, ``python -c "import imcpy"``) run in the same environment."""
    root = Path(__file__).resolve().parents[2]
    if not (root / "pyproject.toml").exists():
        return
    venv = folder / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    python = venv / "bin" / "python"
    paths = "import sysconfig; print(sysconfig.get_path('purelib')); print(sysconfig.get_path('platlib'))"
    own = subprocess.run([str(python), "-c", paths], check=True, capture_output=True, text=True).stdout.split()
    ours = sorted({sysconfig.get_path("purelib"), sysconfig.get_path("platlib")})
    (Path(own[0]) / "imc_conformance_dependencies.pth").write_text("\n".join(ours) + "\n", encoding="utf-8")
    pip = [sys.executable, "-m", "pip", "--disable-pip-version-check", "-q"]
    with tempfile.TemporaryDirectory(prefix="imc-conformance-wheel-") as build:
        subprocess.run([*pip, "wheel", "--no-deps", "-w", build, str(root)], check=True, cwd=build)
        wheel = next(Path(build).glob("*.whl"))
        subprocess.run([*pip, "--python", str(python), "install", "--no-deps", str(wheel)], check=True, cwd=build)
    INSTALLED.update(python=str(python), script=str(venv / "bin" / "imc-conformance"))


def command(argv: list[str]) -> list[str]:
    """The command line of ``imc-conformance ARGV``: the installed wheel's script when the benchmark made one."""
    if INSTALLED:
        return [INSTALLED["script"], *argv]
    return [sys.executable, "-m", "imc_conformance.cli", *argv]


def whole(argv: list[str], env: dict) -> float:
    """Seconds of one whole command (its exit code 0 or 1 expected)."""
    start = time.perf_counter()
    done = subprocess.run(command(argv), stdout=subprocess.DEVNULL,
                          stderr=subprocess.PIPE, text=True, env=env, cwd=tempfile.gettempdir())
    took = time.perf_counter() - start
    if done.returncode not in (0, 1):
        raise SystemExit(f"imc-conformance {' '.join(argv)} failed ({done.returncode}): {done.stderr.strip()[:300]}")
    return took


def bare(argv: list[str], env: dict) -> float:
    """Seconds of the interpreter alone running ``argv`` (the anchor of the start-up ratios)."""
    start = time.perf_counter()
    subprocess.run([INSTALLED.get("python", sys.executable), *argv], check=True, env=env, cwd=tempfile.gettempdir())
    return time.perf_counter() - start
