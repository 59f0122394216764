"""The whole protocol: generation from an IMC.xml, the imc-full folder built on first use, a selection and a run."""

from __future__ import annotations

import tempfile
from pathlib import Path

from ..core.cases import expectation
from ..files import open_corpus
from .measure import EDITION, command_env, median_of, whole


def whole_rows(repeat: int) -> dict[str, float]:
    """The whole protocol, whole processes: generation, the first use of imc-full (a cache holding only the IMC.xml),
    a selection from it, and a run of it with imcpy per case beside the seed suite's."""
    import shutil

    from ..suites.imc.imc_xml import fetch_imc_xml

    xml, env = fetch_imc_xml(), command_env()
    out = {}
    with tempfile.TemporaryDirectory(prefix="imc-conformance-whole-") as folder:
        out["whole generate"] = median_of(min(repeat, 3), lambda: whole(
            ["generate", "--from", str(xml), "--out", str(Path(folder) / "out")], env))

        def first():
            with tempfile.TemporaryDirectory(prefix="imc-conformance-cache-") as cache:
                shutil.copy(xml, Path(cache) / xml.name)
                whole(["list", "--suite", "imc-full", "--message", "EstimatedState"], command_env(cache))
        out["whole first"] = median_of(min(repeat, 3), first)
    whole(["list", "--suite", "imc-full", "--message", "Heartbeat"], env)  # the folder built in this cache
    out["whole list"] = median_of(repeat, lambda: whole(["list", "--suite", "imc-full", "--message", "EstimatedState"], env))
    out["seed list"] = median_of(repeat, lambda: whole(["list", "--message", "LblRange"], env))
    out["whole list ratio"] = out["whole list"] / out["seed list"]
    counts = {}
    for suite in ("imc", "imc-full"):
        counts[suite] = sum(c.kind == "vector" and expectation(c.data, EDITION) is not None
                            for c in open_corpus(suite)[1])
        out[f"whole run {suite}"] = median_of(repeat, lambda s=suite: whole(
            ["run", "--suite", s, "--adapter", "imcpy", "--no-progress"], env))
    out["whole ratio"] = (out["whole run imc-full"] / counts["imc-full"]) / (out["whole run imc"] / counts["imc"])
    print(f"whole protocol: generate --from IMC.xml {out['whole generate']:.1f} s; imc-full built on first use "
          f"{out['whole first']:.1f} s; list one message {out['whole list'] * 1e3:.0f} ms (the seed suite's: "
          f"{out['seed list'] * 1e3:.0f} ms); run with imcpy "
          f"{out['whole run imc-full']:.2f} s for {counts['imc-full']:,} cases against {out['whole run imc']:.2f} s for "
          f"{counts['imc']:,} (per case {out['whole ratio']:.2f}x)")
    return out
