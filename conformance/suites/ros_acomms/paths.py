"""Where the ros_acomms suite's packaged data lives (``vectors/ros_acomms``)."""

from __future__ import annotations

from pathlib import Path

from ...paths import VECTORS

ROS = VECTORS / "ros_acomms"


def ros_data(*parts: str) -> Path:
    return ROS.joinpath(*parts)
