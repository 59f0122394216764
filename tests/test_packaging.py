"""What users install is the wheel: every package and data file of the checkout must be in it, and building it says
nothing setuptools will stop accepting. The package list in pyproject.toml is written by hand (the installed names are
remapped: conformance/ is imc_conformance), so this test derives it from the folders and fails when the two differ.
(.ci/run also builds the wheel and runs both suites from it, outside the checkout.)"""

from __future__ import annotations

import fnmatch
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

CHECKOUT = Path(__file__).resolve().parents[1]


def settings() -> dict:
    return tomllib.loads((CHECKOUT / "pyproject.toml").read_text(encoding="utf-8"))["tool"]["setuptools"]


def test_every_folder_the_wheel_holds_is_listed():
    """Every folder of modules or of data files, named as Python would import it (a file in a folder whose name is
    no identifier, such as ``cpp/dune-imc``, belongs to the nearest one above it): setuptools warns of one left out
    of ``packages`` (its files are shipped today, not for long)."""
    config = settings()
    listed = set(config["packages"])
    found = set()
    for name, folder in config["package-dir"].items():
        root = CHECKOUT / folder
        found.add(name)
        for path in root.rglob("*"):
            parts = path.relative_to(root).parts[:-1]
            if not path.is_file() or path.suffix == ".pyc" or "__pycache__" in parts:
                continue
            owner = next((i for i, part in enumerate(parts) if not part.isidentifier()), len(parts))
            found.add(".".join([name, *parts[:owner]]))
    assert found == listed, f"missing from pyproject.toml: {sorted(found - listed)}; stale: {sorted(listed - found)}"


def package_folders(config: dict) -> dict[str, Path]:
    """Every listed package's folder in the checkout."""
    out = {}
    for package in config["packages"]:
        root = max((name for name in config["package-dir"] if package == name or package.startswith(name + ".")), key=len)
        out[package] = CHECKOUT / config["package-dir"][root] / Path(*package.split(".")[len(root.split(".")):])
    return out


def test_every_data_file_is_packaged():
    config = settings()
    folders = package_folders(config)
    unpackaged = []
    for root in {CHECKOUT / folder for folder in config["package-dir"].values()}:
        for path in root.rglob("*"):
            if not path.is_file() or path.suffix in (".py", ".pyc") or "__pycache__" in path.parts:
                continue
            if not any(fnmatch.fnmatch(relative, p) and relative.count("/") == p.count("/")
                       for owner, folder in folders.items() if path.is_relative_to(folder)
                       for relative in [path.relative_to(folder).as_posix()]
                       for p in config.get("package-data", {}).get(owner, [])):
                unpackaged.append(path.relative_to(CHECKOUT).as_posix())
    assert unpackaged == []


def test_the_build_says_nothing_deprecated(tmp_path):
    """``make dist``'s build (sdist, then the wheel from it) from a copy of the sources: no deprecation notice, no
    folder absent from the packages configuration, nothing setuptools asks to change before it stops working."""
    source = tmp_path / "source"
    source.mkdir()
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(CHECKOUT / name, source / name)
    for name in set(settings()["package-dir"].values()):
        shutil.copytree(CHECKOUT / name, source / name, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    done = subprocess.run([sys.executable, "-m", "build", "--no-isolation", "--outdir", str(tmp_path / "dist"),
                           str(source)], capture_output=True, text=True, timeout=300, cwd=tmp_path)
    out = done.stdout + done.stderr
    assert done.returncode == 0, out[-3000:]
    said = [line.strip() for line in out.splitlines()
            if any(w in line.lower() for w in ("deprecat", "absent from", "no longer supported", "will be removed",
                                               "update your project"))]
    assert said == []
    assert sorted(p.suffix for p in (tmp_path / "dist").iterdir()) == [".gz", ".whl"]
