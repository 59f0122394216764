"""The real IMC.xml that imcpy 1.1.2 was built from, fetched from the imcpy sdist on PyPI and cached.

Never committed: ``pip download`` brings the sdist (which also carries DUNE's source, built by ``make dune``), the
XML is extracted into the cache directory (``$IMC_CONFORMANCE_CACHE``, else ``~/.cache/imc-conformance``).
"""

from __future__ import annotations

import sys
from pathlib import Path

from ...cache import cache_dir

IMCPY_VERSION = "1.1.2"
_MEMBER = f"imcpy-{IMCPY_VERSION}/imc/IMC.xml"


def imcpy_sdist(timeout: float = 300) -> Path:
    """The imcpy source distribution (it holds IMC.xml and DUNE's whole source), downloaded once into the cache."""
    target = cache_dir() / f"imcpy-{IMCPY_VERSION}.tar.gz"
    if target.exists():
        return target
    import subprocess
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, "-m", "pip", "download", "--no-deps", "--no-binary", ":all:",
               "--no-build-isolation", "--disable-pip-version-check", "-d", tmp, f"imcpy=={IMCPY_VERSION}"]
        done = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
        if done.returncode != 0:
            raise RuntimeError(f"could not download the imcpy {IMCPY_VERSION} sdist: {done.stderr.strip()[-500:]}")
        partial = target.with_suffix(".part")
        partial.write_bytes(next(Path(tmp).glob("imcpy-*.tar.gz")).read_bytes())
        partial.replace(target)
    return target


def fetch_imc_xml(timeout: float = 300) -> Path:
    """Path of the cached IMC.xml, taken from the imcpy sdist."""
    target = cache_dir() / f"IMC-imcpy-{IMCPY_VERSION}.xml"
    if target.exists():
        return target
    import tarfile

    sdist = imcpy_sdist(timeout)
    with tarfile.open(sdist) as tar:
        member = tar.extractfile(_MEMBER)
        if member is None:
            raise RuntimeError(f"{sdist.name} has no {_MEMBER}")
        partial = target.with_suffix(".part")
        partial.write_bytes(member.read())
        partial.replace(target)
    return target


def parse_imc_xml(path: Path):
    """The root element of an IMC.xml (ElementTree)."""
    import xml.etree.ElementTree as ET

    return ET.parse(path).getroot()
