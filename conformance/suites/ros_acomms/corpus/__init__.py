"""Builds the ros_acomms corpus under ``vectors/ros_acomms/cases`` from the definitions, deterministically."""
