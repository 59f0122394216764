"""The ros_acomms suite: WHOI's ros_acomms_msgs message and service types (seed 004), as ROS 1 byte vectors
with the MD5 and full definition text of every type."""


def load(folder=None):
    """The suite over its packaged data, or over a folder given instead (``suite.load``, imported when called)."""
    from .suite import load as load_suite

    return load_suite(folder)
