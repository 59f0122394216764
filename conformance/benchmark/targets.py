"""The targets: what each row must meet, and one line per target saying plainly whether it was met."""

from __future__ import annotations


from .measure import COUNTS


# (what, row, kind, bound, before): "s" and "ms": at most the bound; "x": a ratio at most the bound; a rate
# ("cases/s", "frames/s"): at least the bound, from a row of seconds and COUNTS[row]. ``before``: the figure
# measured before the start-up work, or None: issue 20's own measurements, but 5.8 (the README's benchmark table
# before that work, commit c76295d); the live rows' are issue 36's: 10.2 and 1.0 this benchmark's protocol-time rows at
# 6ad7083 (63 scenarios), where the reference node's set took 56.525 s of protocol time (its bound: no slower than
# that); the three start-up ratios' are issue 51's (from the wheel: 6.3, 11.9 and 1.91).
TARGETS = (
    ("--version, whole process", "version", "ms", 100, 354),
    ("list, whole process", "list", "ms", 150, 458),
    ("run --adapter imcpy --message LblRange, whole process", "one message", "ms", 250, 660),
    ("whole IMC corpus with imcpy, empty cache, whole process", "first run", "s", 1.5, 9.0),
    ("in-process, zero-cost adapter", "zero", "cases/s", 100_000, None),
    ("in-process, imcpy", "library", "cases/s", 40_000, 17_328),
    ("in-process, imcpy vs imcpy's bare calls", "imcpy ratio", "x", 1.75, 5.8),
    ("ros_acomms in-process, rosbags vs rosbags' bare calls", "rosbags ratio", "x", 3.0, 13.6),
    ("JSON report per case", "render json", "us", 10, None),
    ("JUnit report per case", "render junit", "us", 10, None),
    ("Markdown report per case", "render markdown", "us", 10, None),
    ("HTML report per case", "render html", "us", 10, None),
    ("subprocess, imcpy shim, batched", "subprocess", "cases/s", 15_000, 7_579),
    ("subprocess, imcpy shim, one request per line", "subprocess per line", "cases/s", 8_000, 7_579),
    ("capture judged, whole command", "capture", "frames/s", 150_000, 61_614),
    ("uncompressed LSF log judged, whole command", "log", "frames/s", 100_000, None),
    ("gzip LSF log vs the same log uncompressed, whole command", "log gzip ratio", "x", 1.5, None),
    ("peak memory judging a ~1 GB LSF log vs a ~100 MB one, whole command", "log memory ratio", "x", 1.25, None),
    ("--version vs a bare python -c pass, whole processes", "version ratio", "x", 4.0, 6.3),
    ("list vs a bare python -c pass, whole processes", "list ratio", "x", 8.0, 11.9),
    ("run --adapter imcpy --message LblRange vs a bare python -c 'import imcpy', whole processes", "one message ratio",
     "x", 1.5, 1.91),
    ("the reference node's scenario set (protocol time)", "live reference", "s", 56.525, None),
    ("slowest broken node vs the reference node, scenario set (protocol time)", "live ratio", "x", 3.0, 10.2),
    ("median broken node vs the reference node, scenario set (protocol time)", "live median ratio", "x", 1.5, 1.0),
    ("fuzz: generated round-trips against imcpy in-process, through hypothesis", "fuzz hypothesis", "examples/s", 500,
     None),
    ("fuzz: frame-mutation sweep of corpus frames against imcpy in-process", "fuzz sweep", "frames/s", 20_000, None),
    ("fuzz: differential, 1,000 examples per message, imcpy vs pyimclsts, whole process", "fuzz differential", "s",
     300, None),
    ("mutants of both suites, corpus and fuzzer", "mutants", "s", 180, None),
    ("whole protocol: generate --from IMC.xml (338 messages), whole process", "whole generate", "s", 30, None),
    ("whole protocol: the imc-full folder built on first use, whole process", "whole first", "s", 30, None),
    ("whole protocol: list --suite imc-full --message EstimatedState vs list --message LblRange, whole processes",
     "whole list ratio", "x", 1.25, None),
    ("whole protocol: run --suite imc-full --adapter imcpy, time per case vs the seed suite's", "whole ratio", "x",
     2.0, None),
    ("relay under a flood of 65,507-byte datagrams with --impair delay=2: peak memory, whole command", "relay flood",
     "MB", 300, None),
    ("the reference node's slowest QUERY reply under 1,000,000 samples, whole process", "node flood reply 1000000", "s",
     2.0, None),
    ("the reference node's peak memory under 1,000,000 samples vs at rest, whole process", "node flood memory ratio",
     "x", 1.5, None),
)


def target_lines(medians: dict[str, float]) -> list[str]:
    """One line per target measured in this run, saying plainly whether it was met, with the earlier figure."""
    lines = []
    for what, row, kind, bound, before in TARGETS:
        if row not in medians:
            continue
        value = medians[row]
        if kind in ("cases/s", "frames/s", "examples/s"):
            value = COUNTS[row] / value
            met, shown, goal = value >= bound, f"{value:,.0f} {kind}", f">= {bound:,} {kind}"
            was = f"{before:,} {kind}" if before else None
        else:
            scale = {"ms": 1e3, "us": 1e6, "s": 1, "x": 1, "MB": 1}[kind]
            value *= scale
            met, shown, goal = value <= bound, f"{value:,.{2 if kind == 'x' else 3 if kind == 's' else 0}f} {kind}", \
                f"<= {bound:g} {kind}"
            was = f"{before:g} {kind}" if before else None
        lines.append(f"target {what}: {shown} ({goal}): {'met' if met else 'MISSED'}"
                     + (f"; before: {was}" if was else ""))
    return lines
