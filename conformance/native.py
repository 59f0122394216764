"""Building what adapters need outside Python, into the cache folder (never the checkout, never system-wide):
Debian's packages fetched with ``apt-get download`` and unpacked with ``dpkg -x``, and C++ programs compiled with
the machine's ``g++``, each object once per content (sources, flags and compiler: a changed input recompiles)."""

from __future__ import annotations

import fcntl
import functools
import hashlib
import json
import os
import shutil
import tarfile
import subprocess
import tempfile
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from pathlib import Path

from .cache import cache_dir

TIMEOUT = 900  # seconds for one download or compile step: a stuck step is an error, not a hang


class BuildError(RuntimeError):
    """A step failed; the message says which, with the tail of its output or the path of its log."""


def run(argv: list, what: str, **options) -> subprocess.CompletedProcess:
    """Run one step (an argv, never a shell); BuildError with the last line of its output if it fails."""
    try:
        done = subprocess.run([str(a) for a in argv], capture_output=True, text=True, timeout=TIMEOUT,
                              stdin=subprocess.DEVNULL, **options)
    except (OSError, subprocess.TimeoutExpired) as exc:
        raise BuildError(f"{what}: {exc}") from None
    if done.returncode != 0:
        tail = (done.stderr or done.stdout).strip().splitlines()[-1:] or ["no output"]
        raise BuildError(f"{what} failed: {tail[0][:300]}")
    return done


@contextmanager
def locked(folder: Path):
    """Hold an exclusive lock on ``folder`` (created if need be): one process at a time builds what is in it
    (pytest-xdist workers, two runs side by side)."""
    folder.mkdir(parents=True, exist_ok=True)
    with open(folder / ".lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        yield folder


def debian_packages(name: str, debs: tuple[str, ...]) -> tuple[Path, dict[str, str]]:
    """The root folder the Debian packages ``debs`` are unpacked in (downloaded once, into ``<cache>/<name>``), and
    their versions."""
    folder = cache_dir() / name
    marker = folder / "packages.json"
    if marker.exists():
        return folder / "root", json.loads(marker.read_text(encoding="utf-8"))
    with locked(folder):
        if marker.exists():  # another process fetched them while this one waited
            return folder / "root", json.loads(marker.read_text(encoding="utf-8"))
        return _download(folder, debs)


def _download(folder: Path, debs: tuple[str, ...]) -> tuple[Path, dict[str, str]]:
    marker = folder / "packages.json"
    with tempfile.TemporaryDirectory(dir=folder) as tmp:
        os.chmod(tmp, 0o755)  # apt-get download drops privileges to _apt when it can: let it write here
        run(["apt-get", "download", *debs], f"apt-get download of {', '.join(debs)} (is the apt index there? "
            "apt-get update)", cwd=tmp)
        versions = {}
        for deb in sorted(Path(tmp).glob("*.deb")):
            run(["dpkg", "-x", deb, Path(tmp) / "root"], f"dpkg -x {deb.name}")
            package, version = deb.name.split("_")[:2]
            versions[package] = version.replace("%3a", ":")
        if (folder / "root").exists():
            shutil.rmtree(folder / "root")
        (Path(tmp) / "root").replace(folder / "root")
    marker.write_text(json.dumps(versions, indent=1), encoding="utf-8")
    return folder / "root", versions


def adapter_sources() -> Path:
    """The C++ adapters' sources shipped in the package (``adapters/cpp``)."""
    import importlib

    return Path(importlib.import_module("imc_conformance.adapters").__file__).parent / "cpp"


def digest(*parts) -> str:
    """A short content hash of files (Paths) and values."""
    h = hashlib.sha256()
    for part in parts:
        h.update(part.read_bytes() if isinstance(part, Path) else json.dumps(part, sort_keys=True).encode())
        h.update(b"\0")
    return h.hexdigest()[:16]


@functools.cache
def compiler() -> str:
    """The C++ compiler (``$CXX``, else g++) and its version, for cache keys; BuildError if there is none."""
    cxx = os.environ.get("CXX", "g++")
    version = run([cxx, "--version"], f"{cxx} --version (install g++)").stdout.splitlines()[0]
    return f"{cxx}\0{version}"


def compile_objects(sources: list[Path], flags: list[str], out: Path, *, headers: tuple[Path, ...] = (),
                    jobs: int | None = None) -> list[Path]:
    """Object files for ``sources`` in ``out``, each compiled once per content of source, ``headers`` (files
    whose change recompiles everything), flags and compiler; in parallel."""
    cxx = compiler()
    key = digest(*headers, flags, cxx)
    out.mkdir(parents=True, exist_ok=True)

    def one(source: Path) -> Path:
        obj = out / f"{source.stem}-{digest(source, key)}.o"
        if not obj.exists():
            partial = obj.with_suffix(".part.o")
            run([cxx.split("\0")[0], *flags, "-c", source, "-o", partial], f"compiling {source.name}")
            partial.replace(obj)
        return obj

    with ThreadPoolExecutor(jobs or os.cpu_count() or 1) as pool:
        return list(pool.map(one, sources))


def link(objects: list[Path], target: Path, flags: list[str] = ()) -> Path:
    """Link ``objects`` into the program ``target`` (written whole or not at all)."""
    target.parent.mkdir(parents=True, exist_ok=True)
    partial = target.with_name(target.name + ".part")
    run([compiler().split("\0")[0], *objects, "-o", partial, *flags], f"linking {target.name}")
    partial.replace(target)
    return target


def built(what: str, build) -> Path:
    """``build()``, the path of a program built on first use; any failure of the build (a step, a download, the
    cache folder, an archive) as a BuildError naming ``what``, for a one-line error."""
    try:
        return build()
    except (BuildError, RuntimeError, OSError, ValueError, tarfile.TarError) as exc:
        raise BuildError(f"cannot build the {what}: {exc}") from None
