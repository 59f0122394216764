"""What users install is the wheel: every package and data file of the checkout must be in it. The package list in
pyproject.toml is written by hand (the installed names are remapped: conformance/ is imc_conformance), so this test
derives it from the folders and fails when the two differ. (.ci/run also builds the wheel and runs both suites from
it, outside the checkout.)"""

from __future__ import annotations

import fnmatch
import tomllib
from pathlib import Path

CHECKOUT = Path(__file__).resolve().parents[1]


def settings() -> dict:
    return tomllib.loads((CHECKOUT / "pyproject.toml").read_text(encoding="utf-8"))["tool"]["setuptools"]


def test_every_python_package_of_the_checkout_is_listed():
    config = settings()
    listed = set(config["packages"])
    found = set()
    for name, folder in config["package-dir"].items():
        root = CHECKOUT / folder
        if not (root / "__init__.py").exists() and name not in config.get("package-data", {}):
            continue
        found.add(name)
        for init in root.rglob("__init__.py"):
            if init.parent != root:
                found.add(".".join([name, *init.parent.relative_to(root).parts]))
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
            owner = max((p for p, folder in folders.items() if path.is_relative_to(folder)), key=lambda p: len(p))
            relative = path.relative_to(folders[owner]).as_posix()
            patterns = config.get("package-data", {}).get(owner, [])
            if not any(fnmatch.fnmatch(relative, p) and relative.count("/") == p.count("/") for p in patterns):
                unpackaged.append(path.relative_to(CHECKOUT).as_posix())
    assert unpackaged == []
