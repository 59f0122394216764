"""The ``dune-cpp`` adapter: DUNE's IMC codec in C++ (``adapters/cpp/dune-imc``), built into the cache from the
imcpy sdist's copy of DUNE, the same source imcpy's binding and ``make dune`` compile.

Only what the codec needs is built: DUNE's CMake configuration step (for its generated ``Config.hpp``), then nine
of DUNE's source files (the IMC classes, CRC-16, strings, the concurrency initialiser) and the adapter: 39.5 s on
2 cores from an empty cache with the sdist downloaded (measured 2026-11-25); later runs only check the cached
objects against their sources. The fields each message has come from the suite's ``definitions.json``
(``generate_fields.py``); JSON from Debian's nlohmann-json3-dev, fetched into the cache.
"""

from __future__ import annotations

import sys
from pathlib import Path

from ....cache import cache_dir
from ....native import adapter_sources, built, compile_objects, debian_packages, digest, link, locked, run
from ...imc.paths import IMC
from ..imc_xml import IMCPY_VERSION, imcpy_sdist
from .build import extract

DUNE_SOURCES = ("IMC/Definitions", "IMC/Factory", "IMC/Message", "IMC/Packet", "IMC/Serialization", "IMC/JSON",
                "Algorithms/CRC16", "Utils/String", "Concurrency/Initializer")
FLAGS = ["-std=c++17", "-O2"]


def home() -> Path:
    return cache_dir() / "dune-codec"


def configured(dune: Path) -> Path:
    """The folder of DUNE's generated headers (``DUNE/Config.hpp``), from DUNE's own CMake configuration."""
    out = home() / "config" / digest(imcpy_sdist())
    generated = out / "DUNEGeneratedFiles" / "src"
    if not (generated / "DUNE" / "Config.hpp").exists():
        out.mkdir(parents=True, exist_ok=True)
        run(["cmake", "-DCMAKE_BUILD_TYPE=Release", dune], "configuring DUNE (cmake; install cmake)", cwd=out)
    return generated


def program(say=lambda text: None, definitions: Path = IMC / "definitions.json") -> Path:
    """The adapter program for the messages of ``definitions`` (a suite's definitions.json), built if need be;
    raises BuildError (or RuntimeError for a failed download)."""
    with locked(home()):
        return _build(say, definitions)


def _build(say, definitions: Path) -> Path:
    dune = extract(say)
    generated = configured(dune)
    json_root, _ = debian_packages("debian-nlohmann-json", ("nlohmann-json3-dev",))
    here = adapter_sources()
    gen = home() / "gen" / digest(definitions, here / "dune-imc" / "generate_fields.py")
    if not (gen / "fields.inc").exists():
        gen.mkdir(parents=True, exist_ok=True)
        run([sys.executable, here / "dune-imc" / "generate_fields.py", definitions, gen / "fields.inc"],
            "generating fields.inc from definitions.json")
    flags = [*FLAGS, f"-I{dune / 'src'}", f"-I{generated}"]
    objects = compile_objects([dune / "src" / "DUNE" / f"{name}.cpp" for name in DUNE_SOURCES], flags,
                              home() / "obj", headers=(generated / "DUNE" / "Config.hpp",))
    objects += compile_objects([here / "dune-imc" / "adapter.cpp"],
                               [*flags, f"-I{gen}", f"-I{here / 'common'}", f"-I{json_root / 'usr' / 'include'}",
                                f'-DIMCPY_VERSION="{IMCPY_VERSION}"'], home() / "obj",
                               headers=(gen / "fields.inc", here / "common" / "jsonl.hpp"))
    target = home() / "bin" / digest([o.name for o in objects]) / "dune-imc-adapter"
    return target if target.exists() else link(objects, target)


def argv(definitions: Path = IMC / "definitions.json") -> list[str]:
    """The command line of the dune-cpp adapter for the messages of ``definitions`` (built on first use)."""
    def say(text: str) -> None:
        print(f"dune-cpp: {text}", file=sys.stderr, flush=True)

    return [str(built("dune-cpp adapter", lambda: program(say, definitions)))]
