"""mdle on ROS 2, with no ROS installation: a backend and the simulator as a ROS 2 robot.

* :mod:`mdle.ros2.backend`: :class:`~mdle.ros2.backend.Ros2Backend`, ``mdle run --backend
  ros2``: reads ``scan`` and ``odom``, writes ``cmd_vel``.
* :mod:`mdle.ros2.serve`: ``mdle sim serve --ros2``, the embedded simulator publishing
  ``scan``, ``odom``, ``tf``, ``tf_static`` and ``/clock`` and obeying ``cmd_vel``.
* :mod:`mdle.ros2.dds`: a Cyclone DDS participant with ROS 2's names, QoS and type hashes.
* :mod:`mdle.ros2.types`, :mod:`mdle.ros2.convert`: the messages and their conversions.
* :mod:`mdle.ros2.names`, :mod:`mdle.ros2.typehash`: names and type hashes (pure Python).

Everything but the last two needs the optional extra ``mdle[ros2]`` (``cyclonedds``).
"""
