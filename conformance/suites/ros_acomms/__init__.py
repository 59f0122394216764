"""The ros_acomms suite: WHOI's ros_acomms_msgs message and service types (seed 004), as ROS 1 byte vectors
with the MD5 and full definition text of every type."""

from .suite import RosSuite, load

__all__ = ["RosSuite", "load"]
