"""The speed the global path allows at each station, for beyond the seen horizon.

The local planner sees about 15 m of track; planning to stand still at the
end of that (``horizon_stop``) caps the car near sqrt(2 a_brake 15 m). The car
also carries the global path, so it knows what lies beyond the cones in view:
this module runs the same speed profile (curvature limit, drive and brake
passes, ``planner.speed_profile``) once along the whole global path, and the
autopilot lets the local plan end at the global plan's speed at that station
instead of at 0, or (``AutopilotConfig.speed_source = "global"``) takes
the global plan's speed at every waypoint. Steering still follows only the
cones in view.

A closed path is profiled over three laps and the middle one kept, so the
speed at the start/finish line is that of a flying lap; an open path stops at
its end.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from conesim.planner.config import SpeedProfileConfig
from conesim.planner.geometry import FloatArray, arc_length
from conesim.planner.speed_profile import profile_curvature, speed_profile
from conesim.tracks.global_path import GlobalPath


class GlobalSpeedPlan:
    """Speeds, and the curvature they come from, along the global path.

    Args:
        path: the global path in ``reference``.
        config: the same limits as the local speed profile.

    Attributes:
        points: (k, 2) the path's points in ``reference`` [m] (a loop's first
            point repeated at its end).
        stations: (k,) arc length of the path's points [m].
        speeds: (k,) allowed speed there [m/s].
        curvature: (k,) the path's curvature averaged over
            ``curvature_window``, as the speed profile reads it [1/m].
    """

    def __init__(self, path: GlobalPath, config: SpeedProfileConfig) -> None:
        pts = np.asarray(path.xy, dtype=float)
        self.closed = path.closed
        if self.closed:
            ring = np.vstack([pts, pts[:1]])
            stations = arc_length(ring)
            self.length = float(stations[-1])
            laps = np.vstack([pts, pts, pts, pts[:1]])
            free = dataclasses.replace(config, horizon_stop=False)
            v = speed_profile(laps, free)
            n = len(pts)
            k = profile_curvature(laps, config)
            self.points: FloatArray = ring
            self.stations: FloatArray = stations
            self.speeds: FloatArray = np.append(v[n : 2 * n], v[n])
            self.curvature: FloatArray = np.append(k[n : 2 * n], k[n])
        else:
            self.points = pts
            self.stations = arc_length(pts)
            self.length = float(self.stations[-1])
            self.speeds = speed_profile(pts, dataclasses.replace(config, horizon_stop=True))
            self.curvature = profile_curvature(pts, config)

    def speed_at(self, station: float) -> float:
        """Allowed speed at arc length ``station`` [m] along the global path [m/s]."""
        if self.closed:
            station %= self.length
        return float(np.interp(station, self.stations, self.speeds))

    def speeds_at(self, stations: FloatArray) -> FloatArray:
        """Allowed speeds (n,) [m/s] at arc lengths ``stations`` (n,) [m]."""
        return np.interp(self._wrap(stations), self.stations, self.speeds)

    def curvature_at(self, stations: FloatArray) -> FloatArray:
        """Curvature (n,) [1/m] at arc lengths ``stations`` (n,) [m]."""
        return np.interp(self._wrap(stations), self.stations, self.curvature)

    def points_at(self, stations: FloatArray) -> FloatArray:
        """Points (n, 2) [m] in ``reference`` at arc lengths ``stations`` (n,) [m]
        (a loop's wrap around; an open path's end holds beyond it)."""
        st = self._wrap(stations)
        return np.column_stack(
            [np.interp(st, self.stations, self.points[:, 0]),
             np.interp(st, self.stations, self.points[:, 1])]
        )  # fmt: skip

    def _wrap(self, stations: FloatArray) -> FloatArray:
        st = np.asarray(stations, dtype=float)
        return np.mod(st, self.length) if self.closed else st
