"""Every verdict of both corpora with every adapter, and of the captures in tests/data, pinned: a speed-up must not
change one (the start-up issue), nor may any other change do so unseen. One line per case: its id, its verdict and
a digest of its JSON form (its checks and their verdicts, frames, outcomes, byte differences, errata, timeline) but
for the free text of details, which quotes what the implementation said (imcpy's error text for a frame whose list
count it reads past the buffer names whatever memory it found there: erratum I1).

``python tests/verdict_golden.py --write`` rewrites the pinned files (a deliberate change: review the diff).
"""

from __future__ import annotations

import hashlib
import json
import sys
import tempfile
from pathlib import Path

GOLDEN = Path(__file__).resolve().parent / "golden" / "verdicts"
DATA = Path(__file__).resolve().parent / "data"
IMC_ADAPTERS = ("imcpy", "pyimclsts", "imcpy-shim", "pyimclsts-shim", "dune-cpp")
RUNS = {  # name -> the command line (without --json)
    **{f"imc-{adapter}-{edition}": ["run", "--adapter", adapter, "--edition", edition]
       for adapter in IMC_ADAPTERS for edition in ("imc-5.4.30", "imc-5.4.11")},
    **{f"ros_acomms-{adapter}-{edition}": ["run", "--suite", "ros_acomms", "--adapter", adapter, "--edition", edition,
                                           "--adapter-arg", f"edition={edition}"]
       for adapter in ("rosbags", "genpy", "roscpp") for edition in ("seed", "9.0.0")},
    "capture-dune-seed": ["pcap", str(DATA / "dune-seed.pcapng")],
}


def lines(doc: dict) -> str:
    """The pinned form of a saved result: ``id<TAB>verdict<TAB>digest`` per case, in the result's order."""
    out = []
    for message in doc["messages"]:
        for case in message["cases"]:
            pinned = {k: v for k, v in case.items() if k != "detail"}
            pinned["checks"] = [{k: v for k, v in check.items() if k != "detail"} for check in case["checks"]]
            digest = hashlib.sha256(json.dumps(pinned, sort_keys=True).encode()).hexdigest()[:16]
            out.append(f"{case['id']}\t{case['verdict']}\t{digest}\n")
    return "".join(out)


def judged(name: str) -> str:
    """The pinned form of run ``name``, made now (through the command line, as a user runs it)."""
    from imc_conformance.cli import main

    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "r.json"
        quiet = ["--no-progress"] if RUNS[name][0] == "run" else []
        code = main([*RUNS[name], *quiet, "--json", str(path)])
        assert code in (0, 1), f"{name}: exit {code}"
        return lines(json.loads(path.read_text(encoding="utf-8")))


if __name__ == "__main__" and sys.argv[1:] == ["--write"]:
    GOLDEN.mkdir(parents=True, exist_ok=True)
    for run in RUNS:
        (GOLDEN / f"{run}.tsv").write_text(judged(run), encoding="utf-8")
        print(f"wrote {GOLDEN / run}.tsv")
