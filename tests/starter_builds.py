"""Building the starters (adapters/starters/<language>) the way their READMEs say, into the cache folder: once per
content of their sources, whoever asks (pytest-xdist workers wait for the one that builds). Everything downloaded
comes from the registries, into the cache too: Maven Central (Jackson) into a Maven repository of its own, crates.io
(serde_json) into a CARGO_HOME of its own, Debian's cJSON with apt-get download; Go's starter needs only its
standard library. Returns the command line that runs a starter. A toolchain this user cannot run (absent from
PATH, or installed where only another user can read, as rustup under /root is for CI's normal user) is
ToolchainMissing, which the tests skip with its reason unless IMC_CONFORMANCE_REQUIRE_STARTERS is set (CI's run as
root, where every toolchain must build its starter)."""

from __future__ import annotations

import os
import shutil
import sys
from pathlib import Path

from imc_conformance.cache import cache_dir
from imc_conformance.native import adapter_sources, debian_packages, digest, locked, run

LANGUAGES = ("python", "java", "go", "rust", "c")
# The JVM's memory capped below the suite's data-memory limit (--memory-limit, 2048 MB by default): heap, code cache,
# metaspace; one GC thread (adapters/README.md, "Memory limits").
JVM = ["-Xmx256m", "-Xss1m", "-XX:+UseSerialGC", "-XX:ReservedCodeCacheSize=64m", "-XX:MaxMetaspaceSize=128m",
       "-XX:TieredStopAtLevel=1"]


TOOLS = {"python": (sys.executable,), "java": ("mvn", "java"), "go": ("go",), "rust": ("cargo",), "c": (os.environ.get("CC", "cc"),)}


class ToolchainMissing(Exception):
    """A starter's toolchain is not runnable by this user."""


def sources(language: str) -> Path:
    return adapter_sources().parent / "starters" / language


def built(language: str) -> list[str]:
    """The argv of the starter of ``language``, built on first use into ``<cache>/starters``."""
    unusable = [tool for tool in TOOLS[language] if shutil.which(tool) is None]
    if unusable:
        raise ToolchainMissing(f"the {language} starter needs {', '.join(unusable)}, which this user cannot run "
                               "(not on PATH, or not executable here)")
    source = sources(language)
    files = sorted(p for p in source.rglob("*") if p.is_file())
    key = digest(*files, [str(p.relative_to(source)) for p in files])
    root = cache_dir() / "starters"
    with locked(root):
        folder = root / f"{language}-{key}"
        if not (folder / "argv").exists():
            work = root / f"{language}-{key}.part"
            shutil.rmtree(work, ignore_errors=True)
            shutil.copytree(source, work)
            argv = BUILDERS[language](work, root, folder)
            (work / "argv").write_text("\n".join(argv), encoding="utf-8")
            shutil.rmtree(folder, ignore_errors=True)
            work.rename(folder)
    return (folder / "argv").read_text(encoding="utf-8").splitlines()


def _python(work: Path, root: Path, final: Path) -> list[str]:
    return [sys.executable, str(final / "adapter.py")]  # nothing to build: the standard library only


def _java(work: Path, root: Path, final: Path) -> list[str]:
    run(["mvn", "-q", "-B", f"-Dmaven.repo.local={root / 'm2'}", "compile", "dependency:build-classpath",
         "-Dmdep.outputFile=classpath.txt"], "mvn compile (the Java starter)", cwd=work)
    classpath = (work / "classpath.txt").read_text(encoding="utf-8").strip()
    return ["java", *JVM, "-cp", f"{final / 'target' / 'classes'}:{classpath}", "starter.Adapter"]


def _go(work: Path, root: Path, final: Path) -> list[str]:
    env = {**os.environ, "GOCACHE": str(root / "go-build"), "GOPATH": str(root / "go"), "GOFLAGS": "-mod=mod",
           "GOTOOLCHAIN": "local"}
    run(["go", "build", "-o", "starter", "."], "go build (the Go starter)", cwd=work, env=env)
    return [str(final / "starter")]


def _rust(work: Path, root: Path, final: Path) -> list[str]:
    env = {**os.environ, "CARGO_HOME": str(root / "cargo"), "CARGO_TARGET_DIR": str(root / "cargo-target")}
    run(["cargo", "build", "--release", "--quiet"], "cargo build (the Rust starter)", cwd=work, env=env)
    shutil.copy2(root / "cargo-target" / "release" / "starter", work / "starter")
    return [str(final / "starter")]


def _c(work: Path, root: Path, final: Path) -> list[str]:
    packages, _ = debian_packages("starters-cjson", ("libcjson-dev", "libcjson1"))
    lib = next(packages.glob("usr/lib/*/libcjson.so.1")).parent
    run([os.environ.get("CC", "cc"), "-O2", "-Wall", "-Wextra", "-Werror", "-I", packages / "usr" / "include",
         "adapter.c", "-o", "starter", "-L", lib, "-l:libcjson.so.1", f"-Wl,-rpath,{lib}", "-lm"],
        "cc (the C starter)", cwd=work)
    return [str(final / "starter")]


BUILDERS = {"python": _python, "java": _java, "go": _go, "rust": _rust, "c": _c}
