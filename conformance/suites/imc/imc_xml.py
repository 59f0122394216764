"""The real IMC.xml that imcpy 1.1.2 was built from, fetched from the imcpy sdist on PyPI and cached.

Never committed: the sdist (which also carries DUNE's source, built by ``make dune``) is downloaded from the
package index (``$PIP_INDEX_URL``, else PyPI's) as a file, without building it or running any of its code, and
the XML is extracted from it into the cache directory (``$IMC_CONFORMANCE_CACHE``, else
``~/.cache/imc-conformance``). Both are pinned by their SHA-256: a cached copy that is not the pinned one is
fetched or extracted again, never used.
"""

from __future__ import annotations

import hashlib
import os
import re
from pathlib import Path
from urllib.parse import urljoin

from ...cache import cache_dir
from ...inputs import read_bytes

IMCPY_VERSION = "1.1.2"
SDIST = f"imcpy-{IMCPY_VERSION}.tar.gz"
SDIST_SHA256 = "1033e307850a356a0c8991c036ad92d304a7c7d593c78efb4758c034c8e666fe"  # as PyPI's index lists it
SDIST_LIMIT = 64 << 20  # bytes (the sdist is 10 MB)
XML_SHA256 = "50fe4da4573dc5176e55a81e12636f79163d6f75fc516bc5bf522be9addde71c"  # imc/IMC.xml in that sdist
_MEMBER = f"imcpy-{IMCPY_VERSION}/imc/IMC.xml"
INDEX = "https://pypi.org/simple/"


def imcpy_sdist(timeout: float = 300) -> Path:
    """The imcpy source distribution (it holds IMC.xml and DUNE's whole source), downloaded once into the cache;
    RuntimeError with the reason if it cannot be."""
    target = cache_dir() / SDIST
    if _pinned(target, SDIST_SHA256, SDIST_LIMIT):
        return target
    index = os.environ.get("PIP_INDEX_URL") or INDEX
    page = urljoin(index.rstrip("/") + "/", "imcpy/")
    text = _get(page, timeout, 8 << 20).decode("utf-8", "replace")
    links = [urljoin(page, href) for href in re.findall(r'href="([^"]+)"', text)]
    link = next((u for u in links if u.split("#")[0].endswith("/" + SDIST)), None)
    if link is None:
        raise RuntimeError(f"the package index {index} lists no {SDIST}")
    data = _get(link.split("#")[0], timeout, SDIST_LIMIT)
    if hashlib.sha256(data).hexdigest() != SDIST_SHA256:
        raise RuntimeError(f"{link.split('#')[0]}: not the {SDIST} of PyPI (SHA-256 {hashlib.sha256(data).hexdigest()},"
                           f" expected {SDIST_SHA256})")
    _write(target, data)
    return target


def fetch_imc_xml(timeout: float = 300) -> Path:
    """Path of the cached IMC.xml, taken from the imcpy sdist."""
    target = cache_dir() / f"IMC-imcpy-{IMCPY_VERSION}.xml"
    if _pinned(target, XML_SHA256, SDIST_LIMIT):
        return target
    import tarfile

    sdist = imcpy_sdist(timeout)
    with tarfile.open(sdist) as tar:
        member = tar.extractfile(_MEMBER)
        if member is None:
            raise RuntimeError(f"{sdist.name} has no {_MEMBER}")
        data = member.read()
    if hashlib.sha256(data).hexdigest() != XML_SHA256:
        raise RuntimeError(f"{sdist}: its {_MEMBER} is not the one pinned")
    _write(target, data)
    return target


def cached_imc_xml() -> Path | None:
    """Path of the IMC.xml if the cache holds the pinned one, else None: never fetched (for judging traffic, which
    must neither wait on the network nor fail without it)."""
    target = cache_dir() / f"IMC-imcpy-{IMCPY_VERSION}.xml"
    return target if _pinned(target, XML_SHA256, SDIST_LIMIT) else None


def _pinned(path: Path, sha256: str, limit: int) -> bool:
    """Whether ``path`` holds the bytes of that SHA-256."""
    try:
        return hashlib.sha256(read_bytes(path, limit)).hexdigest() == sha256
    except ValueError:  # missing, unreadable, too large
        return False


def _get(url: str, timeout: float, limit: int) -> bytes:
    """At most ``limit`` bytes from ``url`` (http or https); RuntimeError with the reason."""
    from urllib.request import urlopen

    if not url.startswith(("https://", "http://")):
        raise RuntimeError(f"{url}: not an http(s) address")
    try:
        with urlopen(url, timeout=timeout) as response:
            data = response.read(limit + 1)
    except (OSError, ValueError) as exc:
        raise RuntimeError(f"cannot download {url}: {exc}") from None
    if len(data) > limit:
        raise RuntimeError(f"{url}: larger than {limit >> 20} MB")
    return data


def _write(target: Path, data: bytes) -> None:
    partial = target.with_name(f".{target.name}.{os.getpid()}.part")
    partial.write_bytes(data)
    partial.replace(target)


def parse_imc_xml(path: Path):
    """The root element of an IMC.xml (ElementTree)."""
    import xml.etree.ElementTree as ET

    return ET.parse(path).getroot()
