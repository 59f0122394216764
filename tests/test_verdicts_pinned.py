"""Every verdict of both corpora with every adapter (both editions), and of the DUNE capture, is what it was: see
tests/verdict_golden.py, which also rewrites the pinned files after a deliberate change."""

from __future__ import annotations

import pytest

from verdict_golden import GOLDEN, RUNS, judged


@pytest.mark.parametrize("name", RUNS)
def test_every_verdict_is_pinned(name):
    pinned = (GOLDEN / f"{name}.tsv").read_text(encoding="utf-8").splitlines()
    now = judged(name).splitlines()
    changed = sorted(set(now) ^ set(pinned))
    assert not changed, f"{len(changed)} lines differ (- pinned, + now):\n" + "\n".join(
        ("+ " if line in now else "- ") + line for line in changed[:20])
    assert now == pinned  # and in the same order
