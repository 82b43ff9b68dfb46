"""Localization: geodesy, the frame tree (tf2 semantics), GPS/IMU fusion, TF broadcaster.

This package's ``__init__`` stays import-light on purpose: ``localization.pose``,
``localization.geodesy`` (and, later, ``localization.messages``) are dependency-free
leaf modules that the track loader and the simulator's sensor models share, the
way every ROS node shares ``geometry_msgs`` and ``sensor_msgs``.
"""

import logging

# A library logs, the application decides what is shown (the logging HOWTO's
# advice for libraries): without this, Python's last-resort handler printed
# the EKF's warnings to stderr in every script that used the env. The
# ``conesim`` command configures logging (``-v`` shows the warnings).
logging.getLogger(__name__).addHandler(logging.NullHandler())
