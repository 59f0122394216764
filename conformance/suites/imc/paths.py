"""Where the IMC suite's packaged data lives (``vectors/imc``)."""

from __future__ import annotations

from pathlib import Path

from ...paths import VECTORS

IMC = VECTORS / "imc"


def imc_data(*parts: str) -> Path:
    return IMC.joinpath(*parts)
