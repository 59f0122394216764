"""The ``roscpp`` adapter: roscpp's ROS 1 serialization in C++ (``adapters/cpp/roscpp``), built into the cache.

Debian's packages are fetched with ``apt-get download`` and unpacked into the cache (never installed): gencpp and
genmsg (with empy) generate the classes from the package's .msg and .srv text, as catkin would; roscpp_serialization,
rostime and cpp_common, their headers and boost's, and std_msgs' headers compile them. The text is the suite's
edition (``--adapter-arg edition=9.0.0``) or a team's package (``--adapter-arg msgs=DIR``), as for the genpy and
rosbags adapters; one program per text, cached by its hash. About 10 s to compile, after a 10 MB download once.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

from ...cache import cache_dir
from ...native import BuildError, adapter_sources, compile_objects, debian_packages, digest, link, locked, run
from .package_files import source_files

PACKAGE = "ros_acomms_msgs"
DEBS = ("python3-gencpp", "python3-genmsg", "python3-empy", "ros-std-msgs", "libstd-msgs-dev", "libroscpp-core-dev",
        "libroscpp-serialization0d", "librostime1d", "libcpp-common0d", "libboost1.74-dev", "nlohmann-json3-dev")
LIBS = ("roscpp_serialization", "rostime", "cpp_common")
FLAGS = ["-std=c++17", "-O2"]


def generate(root: Path, versions: dict, files: dict[str, str], here: Path) -> Path:
    """The folder holding gencpp's headers (``ros_acomms_msgs/*.h``) and registry.inc, generated once per text."""
    out = cache_dir() / "roscpp-classes" / digest(versions, files, here / "roscpp" / "generate_registry.py")
    if (out / "done").exists():
        return out / "gen"
    src, gen = out / "src", out / "gen"
    for name, text in files.items():
        (src / name).parent.mkdir(parents=True, exist_ok=True)
        (src / name).write_text(text, encoding="utf-8")
    env = {**os.environ, "PYTHONPATH": str(root / "usr/lib/python3/dist-packages")}
    includes = ["-I", f"{PACKAGE}:{src / 'msg'}", "-I", f"std_msgs:{root / 'usr/share/std_msgs/msg'}"]
    for path in sorted([*src.glob("msg/*.msg"), *src.glob("srv/*.srv")]):
        run([sys.executable, root / "usr/lib/gencpp/gen_cpp.py", path, "-p", PACKAGE, "-o", gen / PACKAGE,
             "-e", root / "usr/share/gencpp", *includes], f"gencpp on {path.name}", env=env)
    run([sys.executable, here / "roscpp" / "generate_registry.py", PACKAGE, src, gen / "registry.inc"],
        "generating registry.inc")
    (out / "done").write_text("", encoding="utf-8")
    return gen


def program(edition: str | None = None, msgs: str | None = None) -> Path:
    """The adapter program for an edition or a package folder, built if need be (BuildError if it cannot be)."""
    with locked(cache_dir() / "roscpp-adapter"):
        return _build(edition, msgs)


def _build(edition: str | None, msgs: str | None) -> Path:
    here = adapter_sources()
    root, versions = debian_packages("debian-roscpp", DEBS)
    gen = generate(root, versions, source_files(edition, msgs), here)
    shown = ", ".join(f"{name} {versions[name]}" for name in ("libroscpp-serialization0d", "python3-gencpp"))
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
    try:
        return [str(program(edition, msgs))]
    except (BuildError, RuntimeError, OSError, ValueError) as exc:
        raise BuildError(f"cannot build the roscpp adapter: {exc}") from None
