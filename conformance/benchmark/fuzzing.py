"""Fuzzing rows: the fuzzer's throughput against imcpy, the differential run, the mutants of both suites."""

from __future__ import annotations

import subprocess
import tempfile
import time

from ..files import open_corpus
from .measure import COUNTS, EDITION, command, command_env, timed


def fuzz_rows(suite, everything) -> dict[str, float]:
    """The fuzzer's throughput (once each: hypothesis's search is sequential and seeded) and the mutants' time."""
    import imcpy

    from ..adapters.imcpy_adapter import adapter
    from ..fuzz.engine import Search
    from ..fuzz.mutation import score
    from ..sessions.library import LibrarySession

    source = suite.fuzz_source(EDITION, everything)
    sessions = {"imcpy": LibrarySession(adapter(), "imcpy")}
    search = Search(suite, source, sessions, EDITION, seed=0, budget=100)
    out = {"fuzz hypothesis": timed(lambda: search.run(source.groups, ("message",)))}
    COUNTS["fuzz hypothesis"] = sum(search.tally.judged.values())
    sweep = Search(suite, source, sessions, EDITION, seed=0, budget=1)
    out["fuzz sweep"] = timed(lambda: sweep.sweep(source.groups, 2000))
    COUNTS["fuzz sweep"] = sum(sweep.tally.judged.values())
    rng = __import__("random").Random(0)
    frames = [source.mutate(g, f, e, rng.choice(source.mutations), rng.randrange(1 << 16), rng.randrange(1 << 16))
              for g in source.groups for e, f in source.seed_frames(g)]

    def bare():
        for frame in frames:
            try:
                imcpy.Packet.deserialize(frame)
            except RuntimeError:
                pass
    out["imcpy bare decode"] = timed(bare) / len(frames)
    out["fuzz sweep ratio"] = out["fuzz sweep"] / COUNTS["fuzz sweep"] / out["imcpy bare decode"]
    start = time.perf_counter()
    subprocess.run(command(["fuzz", "--adapter", "imcpy", "--adapter", "pyimclsts", "--seed", "0", "--budget",
                            "500"]), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                   env=command_env(), cwd=tempfile.gettempdir(), check=False)
    out["fuzz differential"] = time.perf_counter() - start
    start = time.perf_counter()
    for name in ("imc", "ros_acomms"):
        s, cases = open_corpus(name)
        edition = s.editions[0]
        vectors = [c for c in cases if c.kind == "vector"]
        source = s.fuzz_source(edition, cases)
        for mutant in s.mutants(edition):
            score(s, mutant, vectors, edition, source, seed=0, budget=40)
    out["mutants"] = time.perf_counter() - start
    print(f"fuzz: {COUNTS['fuzz hypothesis']} generated examples against imcpy in {out['fuzz hypothesis']:.1f} s "
          f"({COUNTS['fuzz hypothesis'] / out['fuzz hypothesis']:,.0f}/s); sweep {COUNTS['fuzz sweep']} frames in "
          f"{out['fuzz sweep']:.2f} s ({COUNTS['fuzz sweep'] / out['fuzz sweep']:,.0f} frames/s, "
          f"{out['fuzz sweep ratio']:.1f}x imcpy's bare decode); differential imcpy vs pyimclsts, 1,000 examples per "
          f"message: {out['fuzz differential']:.0f} s; mutants of both suites: {out['mutants']:.0f} s")
    return out
