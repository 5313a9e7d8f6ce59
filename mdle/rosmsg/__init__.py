"""ROS 2 messages as bytes: the message definitions mdle speaks and their CDR encoding.

Pure Python and below every layer that speaks ROS: the recordings (:mod:`mdle.record`)
and the ROS 2 backend (:mod:`mdle.ros2`) share it, so a message has one definition.
"""
