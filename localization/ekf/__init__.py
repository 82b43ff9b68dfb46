"""GPS/IMU fusion: a filterpy EKF estimating the pose of ``gps_antenna`` in ``reference``.

Spec 000, "Integrating GPS-IMU Fusion into the TF Chain": the filter's output
replaces the raw ``/local_xy`` + ``/global_yaw`` pose in the
``reference -> gps_antenna`` transform (``localization.broadcaster``).

Usage::

    ekf = FusionEkf(for_profile("rtk"))
    for msg in messages:          # NavSatFix, HeadingStamped, Imu, WheelSpeed
        ekf.process(msg)
    if ekf.initialised:
        est = ekf.estimate(t)     # Estimate: pose, speed, yaw rate, covariances

Modules: :mod:`.model` (the state, argued there; the motion model's settings
and typed call), :mod:`.kernels` (the motion model, compiled, with its
derivation and Jacobians), :mod:`.observation` (h(x) and H of each sensor),
:mod:`.config` (settings and per-profile defaults),
:mod:`.measurements` (message checks), :mod:`.history` (late measurements),
:mod:`.filter` (the filter), :mod:`.augmented` (the landmarks' part of
the state beside filterpy's, ``slam``), :mod:`.estimate` (its output), :mod:`.health`
(rejection counters), :mod:`.synthetic` (a synthetic car for consistency tests
and benchmarks; not used by the pipeline).
"""

from __future__ import annotations

from conesim.localization.ekf.config import PROFILES, EkfConfig, for_profile
from conesim.localization.ekf.estimate import Estimate
from conesim.localization.ekf.filter import FusionEkf, NotInitialisedError
from conesim.localization.ekf.health import Health, RejectReason, Sensor, UpdateResult
from conesim.localization.ekf.model import StateLayout

__all__ = [
    "PROFILES",
    "EkfConfig",
    "Estimate",
    "FusionEkf",
    "Health",
    "NotInitialisedError",
    "RejectReason",
    "Sensor",
    "StateLayout",
    "UpdateResult",
    "for_profile",
]
