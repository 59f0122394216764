"""``make dune``: build DUNE, LSTS's onboard software, from the imcpy sdist on PyPI (which ships DUNE's whole
source), once, into the cache folder (``<cache>/dune``), never into the checkout.

The build takes 10 to 30 minutes on 2 cores: the progress of ``make`` is printed as it goes, and a failed step
says where its log is. With the binary built from the same sdist already in the cache, it takes seconds.
"""

from __future__ import annotations

import hashlib
import os
import re
import subprocess
import sys
import tarfile
import time
from pathlib import Path

from ....cache import cache_dir
from ..imc_xml import IMCPY_VERSION, imcpy_sdist

PROGRESS = re.compile(r"^\[\s*(\d+)%\]")


class BuildError(Exception):
    """A step of the build failed; the message says which and where its log is."""


def home() -> Path:
    return cache_dir() / "dune"


def source() -> Path:
    """DUNE's source tree in the extracted sdist."""
    return home() / "src" / f"imcpy-{IMCPY_VERSION}" / "dune"


def binary() -> Path:
    return home() / "build" / "dune"


def built() -> bool:
    """Whether the cached binary was built from the cached sdist."""
    stamp = home() / "build" / "built-from"
    return binary().exists() and stamp.exists() and stamp.read_text() == _digest(imcpy_sdist())


def build(jobs: int | None = None, say=print) -> Path:
    """The DUNE binary, built if need be; raises BuildError naming the log of a failed step."""
    sdist = imcpy_sdist()
    if built():
        say(f"DUNE is built: {binary()} (from the imcpy {IMCPY_VERSION} sdist, cached)")
        return binary()
    started = time.monotonic()
    extract(say)
    out = home() / "build"
    out.mkdir(parents=True, exist_ok=True)
    say("configuring (cmake)")
    _run(["cmake", "-DCMAKE_BUILD_TYPE=Release", str(source())], out, out / "cmake.log", say)
    jobs = jobs or os.cpu_count() or 1
    say(f"building the dune target with {jobs} jobs (10 to 30 minutes on 2 cores); log: {out / 'build.log'}")
    _run(["nice", "-n", "10", "make", f"-j{jobs}", "dune"], out, out / "build.log", say)
    (out / "built-from").write_text(_digest(sdist))
    say(f"DUNE is built: {binary()} in {(time.monotonic() - started) / 60:.1f} min")
    return binary()


def extract(say=print) -> Path:
    """DUNE's source tree, extracted from the cached sdist once."""
    if not source().exists():
        say(f"extracting DUNE's source from {imcpy_sdist().name}")
        with tarfile.open(imcpy_sdist()) as tar:
            _extract_files(tar, home() / "src")
    return source()


def _extract_files(tar: tarfile.TarFile, into: Path) -> None:
    """The archive's folders and regular files, each inside ``into`` (no links, devices or paths out of it):
    what tarfile's "data" filter does, by hand, because Python 3.11 has that filter only from 3.11.4 on."""
    into = into.resolve()
    members = []
    for member in tar.getmembers():
        if not (member.isfile() or member.isdir()):
            continue
        if not (into / member.name).resolve().is_relative_to(into):
            raise BuildError(f"{member.name!r} in the imcpy sdist would be written outside {into}")
        member.mode = (member.mode | 0o600) & 0o755
        members.append(member)
    tar.extractall(into, members=members)


def _run(argv: list[str], cwd: Path, log: Path, say) -> None:
    """Run a build step with its output in ``log``, printing make's progress as it moves on."""
    try:
        with log.open("w") as out:
            proc = subprocess.Popen(argv, cwd=cwd, stdout=out, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
    except OSError as exc:
        raise BuildError(f"{argv[0]} could not run ({exc.strerror or exc}): install it (Debian: cmake, make, g++)") from exc
    shown, last = -1, time.monotonic()
    while proc.poll() is None:
        time.sleep(2)
        percent = _progress(log)
        if percent is not None and (percent != shown or time.monotonic() - last > 60):
            say(f"  {percent:3d}% ({log.name})")
            shown, last = percent, time.monotonic()
    if proc.returncode != 0:
        raise BuildError(f"{' '.join(argv[:2])} failed (exit {proc.returncode}); its log: {log}")


def _progress(log: Path) -> int | None:
    """The last percentage make printed."""
    try:
        with log.open("rb") as f:
            f.seek(max(0, log.stat().st_size - 4096))
            tail = f.read().decode("utf-8", "replace").splitlines()
    except OSError:
        return None
    found = [int(m[1]) for line in tail if (m := PROGRESS.match(line))]
    return found[-1] if found else None


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def main() -> int:
    try:
        build(say=lambda text: print(text, flush=True))
    except (BuildError, RuntimeError) as exc:
        print(f"make dune: {exc}", file=sys.stderr)
        return 1
    return 0
