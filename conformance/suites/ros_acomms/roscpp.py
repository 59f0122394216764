"""The ``roscpp`` adapter: roscpp's ROS 1 serialization in C++ (``adapters/cpp/roscpp``), built into the cache.

Debian's packages are fetched with ``apt-get download`` and unpacked into the cache (never installed): gencpp and
genmsg (with empy) generate the classes from the package's .msg and .srv text, as catkin would; roscpp_serialization,
rostime and cpp_common, their headers and boost's, and std_msgs' headers compile them. The text is the suite's
edition (``--adapter-arg edition=9.0.0``) or a team's package (``--adapter-arg msgs=DIR``), as for the genpy and
rosbags adapters; one program per text, cached by its hash. 17.3 s on 2 cores from an empty cache, the 10 MB
download included (measured 2026-11-25).
"""

from __future__ import annotations

import sys
from pathlib import Path

from ...cache import cache_dir
from ...native import adapter_sources, built, compile_objects, debian_packages, digest, link, locked, run
from .package_files import generated_package, source_files

PACKAGE = "ros_acomms_msgs"
DEBS = ("python3-gencpp", "python3-genmsg", "python3-empy", "ros-std-msgs", "libstd-msgs-dev", "libroscpp-core-dev",
        "libroscpp-serialization0d", "librostime1d", "libcpp-common0d", "libboost1.74-dev", "nlohmann-json3-dev")
LIBS = ("roscpp_serialization", "rostime", "cpp_common")
FLAGS = ["-std=c++17", "-O2"]


def generate(root: Path, versions: dict, files: dict[str, str], here: Path) -> Path:
    """The folder holding gencpp's headers (``ros_acomms_msgs/*.h``) and registry.inc, generated once per text."""
    registry = here / "roscpp" / "generate_registry.py"

    def make(src: Path, gen: Path, env: dict, includes: list[str]) -> None:
        for path in sorted([*src.glob("msg/*.msg"), *src.glob("srv/*.srv")]):
            run([sys.executable, root / "usr/lib/gencpp/gen_cpp.py", path, "-p", PACKAGE, "-o", gen / PACKAGE,
                 "-e", root / "usr/share/gencpp", *includes], f"gencpp on {path.name}", env=env)
        run([sys.executable, registry, PACKAGE, src, gen / "registry.inc"], "generating registry.inc")

    return generated_package("roscpp", PACKAGE, root, versions, files, make, registry)


def program(edition: str | None = None, msgs: str | None = None) -> Path:
    """The adapter program for an edition or a package folder, built if need be (BuildError if it cannot be)."""
    with locked(cache_dir() / "roscpp-adapter"):
        return _build(edition, msgs)


def _build(edition: str | None, msgs: str | None) -> Path:
    here = adapter_sources()
    root, versions = debian_packages("debian-roscpp", DEBS)
    gen = generate(root, versions, source_files(edition, msgs), here)
    shown = ", ".join(f"{name} {versions.get(name, '?')}" for name in ("libroscpp-serialization0d", "python3-gencpp"))
    lib = root / "usr/lib/x86_64-linux-gnu"
    objects = compile_objects([here / "roscpp" / "adapter.cpp"],
                              [*FLAGS, f"-I{gen}", f"-I{root / 'usr/include'}", f"-I{here / 'common'}",
                               f'-DROSCPP_ADAPTER_VERSIONS="(Debian {shown})"'],
                              cache_dir() / "roscpp-adapter" / "obj",
                              headers=(*sorted(gen.rglob("*.h")), gen / "registry.inc", here / "common" / "jsonl.hpp"))
    target = cache_dir() / "roscpp-adapter" / "bin" / digest([o.name for o in objects]) / "roscpp-adapter"
    if target.exists():
        return target
    return link(objects, target, [f"-L{lib}", *(f"-l{name}" for name in LIBS), f"-Wl,-rpath,{lib}"])


def argv(edition: str | None = None, msgs: str | None = None) -> list[str]:
    """The command line of the roscpp adapter (built on first use)."""
    return [str(built("roscpp adapter", lambda: program(edition, msgs)))]
