"""EKF-SLAM on cone landmarks: the first lap builds the map, later laps localize against it.

Why EKF-SLAM in the fusion filter's state rather than a smoother (GTSAM's
iSAM2): the fusion filter is already the car's one estimator (filterpy's
EKF with GPS, heading, wheel speed and the IMU, late messages replayed), and
a track has a few hundred cones, so the landmarks join its state (n of a few
hundred) and every sensor keeps one model, one gate and one set of
counters; a second estimator would need its own copy of each, and a new
dependency. The landmarks' covariance is held beside filterpy's vehicle
block in a compressed form (``localization.ekf.augmented``): the fixes,
headings, wheel speeds and IMU samples between two scans cost what they
cost without a map, and a scan O(L) once the map is frozen, O(L^2) while it
is built. The map's cross-correlations with the pose stay, so the cone
updates' NIS stays honest (measured in ``benchmarks/bench_slam.py``).

The map's frame is the start's: the car starts on the track's start pose
(a track asset, as the global path is) to ``start_sigma``, not at its first
GPS fix, so a consumer receiver's 2 m error becomes its bias state's
estimate instead of the map's offset.

Modules: :mod:`.config` (settings), :mod:`.book` (candidates, colours, hits
and misses beside the state), :mod:`.update` (the scan step: association,
the joint update, the map step). Association, the observation model and
the gates are the map mode's (``localization.cones``).
"""

from __future__ import annotations

from conesim.localization.slam.book import MapBook
from conesim.localization.slam.config import SlamConfig
from conesim.localization.slam.update import SlamUpdate

__all__ = ["MapBook", "SlamConfig", "SlamUpdate"]
