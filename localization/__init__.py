"""Localization: the frame tree (tf2 semantics), GPS/IMU fusion, the TF broadcaster.

Measurements in, the ``reference -> gps_antenna -> os_sensor`` frame tree
out (spec 000). Imports ``conesim.core`` and ``conesim.tracks`` only: never
the simulator, whose truth the car's software cannot see.
"""
