"""The screenshot of the HTML report that the README and the manual show, taken in Debian's headless Chromium.

``make screenshot`` (``python docs/tools/screenshot.py docs/images/html-report.png``) regenerates the committed
image; ``tests/test_docs.py`` takes it into a temporary folder, so the code that made the committed one runs in CI.
The report is a real run: pyimclsts judged on LblRange's CRC cases, each an invalid frame it accepts (erratum P1), so
the first failing case shows the frame given beside what pyimclsts read from it, the differing byte named, at a width
a page of the manual or a forge shows without shrinking the text much."""

from __future__ import annotations

import subprocess
import sys
import tempfile
from pathlib import Path

CHROMIUM = Path("/usr/bin/chromium")
WINDOW = "1000,1000"
SELECTION = ("--message", "LblRange", "--id", "imc/LblRange/crc/*")


def chromium(*args: str, profile: Path, timeout: float = 60) -> subprocess.CompletedProcess:
    """Headless Chromium with a profile of its own, nothing fetched in the background; fails unless it exits 0."""
    argv = [str(CHROMIUM), "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
            "--disable-background-networking", "--disable-component-update", "--disable-sync", "--hide-scrollbars",
            f"--user-data-dir={profile}", *args]
    done = subprocess.run(argv, capture_output=True, text=True, timeout=timeout)
    if done.returncode != 0:
        raise RuntimeError(f"chromium exited {done.returncode}: {done.stderr[-2000:]}")
    return done


def report_screenshot(out: Path, workdir: Path) -> Path:
    """Run the suite into ``workdir`` and write the screenshot of its HTML report to ``out`` (a PNG)."""
    cli = Path(sys.executable).with_name("imc-conformance")
    html = workdir / "report.html"
    done = subprocess.run([str(cli), "run", "--adapter", "pyimclsts", *SELECTION, "--no-progress", "--html", str(html)],
                          cwd=workdir, capture_output=True, text=True, timeout=300)
    if done.returncode != 1 or not html.exists():  # pyimclsts fails LblRange: exit 1, with the report written
        raise RuntimeError(f"the run exited {done.returncode}: {done.stderr[-2000:]}")
    out.parent.mkdir(parents=True, exist_ok=True)
    chromium(f"--screenshot={out.resolve()}", f"--window-size={WINDOW}", html.as_uri(), profile=workdir / "profile")
    return out


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: python docs/tools/screenshot.py OUT.png")
    with tempfile.TemporaryDirectory() as tmp:
        print(report_screenshot(Path(sys.argv[1]), Path(tmp)))
