"""Settings of the cone update: the detector's noise as the team knows it, gates, colours."""

from __future__ import annotations

import math
from dataclasses import dataclass

from conesim.core.messages import FRAME_OS_SENSOR


@dataclass(frozen=True, slots=True)
class ConeUpdateConfig:
    """How cone detections update the filter (``localization.cones``).

    Attributes:
        range_sigma: the detector's range noise [m] (its datasheet; the sensors' config).
        bearing_sigma: the detector's bearing noise [rad].
        map_sigma: each map cone's survey error per axis assumed [m].
        map_bias_sigma: the whole map's offset assumed, per axis [m]; > 0 puts
            it in the filter's state (``localization.ekf.model``).
        min_range: nearest range the detector sees [m] (for counting misses).
        max_range: farthest range the detector sees [m].
        fov: the detector's field of view [rad].
        sensor_offset: the sensor's planar origin in the antenna frame (x, y) [m].
        gate_probability: chi-square probability of each pair's Mahalanobis gate
            and of the scan's joint NIS gate [-], in (0, 1).
        use_colours: whether a reported colour must match the map cone's.
        consensus_tolerance: how far two associations' offsets may differ and
            still agree, beyond the yaw uncertainty's share [m].
        min_consensus: detections that must agree on an offset where
            associations are ambiguous [-].
        max_search_radius: largest radius searched for candidates around a
            predicted detection [m].
        sensor_frame: the frame of the detections.
    """

    range_sigma: float = 0.05  # [m]
    bearing_sigma: float = 0.007  # [rad]
    map_sigma: float = 0.03  # [m]
    map_bias_sigma: float = 0.02  # [m]
    min_range: float = 0.0  # [m]
    max_range: float = 15.0  # [m]
    fov: float = math.pi  # [rad]
    sensor_offset: tuple[float, float] = (0.0, 0.0)  # [m]
    gate_probability: float = 0.999  # [-]
    use_colours: bool = True
    consensus_tolerance: float = 0.3  # [m]
    min_consensus: int = 3  # [-]
    max_search_radius: float = 6.0  # [m]
    sensor_frame: str = FRAME_OS_SENSOR

    def __post_init__(self) -> None:
        for name in (
            "range_sigma",
            "bearing_sigma",
            "map_sigma",
            "map_bias_sigma",
            "min_range",
            "consensus_tolerance",
        ):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(
                    f"ConeUpdateConfig.{name} = {value!r} is out of range: allowed >= 0"
                )
        for name in ("max_range", "fov", "max_search_radius"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(
                    f"ConeUpdateConfig.{name} = {value!r} is out of range: allowed > 0"
                )
        if self.range_sigma == 0.0 and self.bearing_sigma == 0.0 and self.map_sigma == 0.0:
            raise ValueError("ConeUpdateConfig: range_sigma, bearing_sigma and map_sigma are all 0")
        if not 0.0 < self.gate_probability < 1.0:
            raise ValueError(
                f"ConeUpdateConfig.gate_probability = {self.gate_probability!r} is out of "
                "range: allowed (0, 1)"
            )
        if isinstance(self.min_consensus, bool) or self.min_consensus < 1:
            raise ValueError(
                f"ConeUpdateConfig.min_consensus = {self.min_consensus!r}: allowed >= 1"
            )
