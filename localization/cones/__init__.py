"""Localization against a known cone map: each detection scan updates the fusion EKF's pose.

The map is the track's cones as a survey gives them (``tracks.survey``), in
``reference``. Each scan's detections are associated with map cones
(:mod:`.association`: a k-d tree for candidates, a Mahalanobis gate on the
predicted positions, colours where trusted, and a consensus with a joint
compatibility check where cones are dense), and the associated ones update
the filter's pose through filterpy's EKF update (:mod:`.observation` is the
model, :class:`~.update.ConeUpdate` the step the filter calls). Rejected
detections are counted in the filter's ``Health`` (``ConeCounts``), never
folded in.

Modules: :mod:`.config` (settings), :mod:`.landmarks` (the map and its
index), :mod:`.observation` (h(x), H and the detections' covariance),
:mod:`.association`, :mod:`.update`.
"""

from __future__ import annotations

from conesim.localization.cones.config import ConeUpdateConfig
from conesim.localization.cones.landmarks import LandmarkMap
from conesim.localization.cones.update import ConeUpdate

__all__ = ["ConeUpdate", "ConeUpdateConfig", "LandmarkMap"]
