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
from conesim.planner.geometry import FloatArray
from conesim.planner.speed_profile import profile_curvature, speed_profile
from conesim.tracks.global_path import GlobalPath


class GlobalSpeedPlan:
    """Speeds, and the curvature they come from, along the global path.

    Args:
        path: the global path in ``reference``.
        config: the same limits as the local speed profile.

    Attributes:
        line: the path (``GlobalPath.polyline``).
        closed: whether it is a loop.
        length: where its stations end [m] (``Polyline.end_station``).
        points: (k, 2) the path's points in ``reference`` [m] (a loop's first
            point repeated at its end: ``line.ring``).
        stations: (k,) arc length of the path's points [m] (``line.stations``).
        speeds: (k,) allowed speed there [m/s].
        curvature: (k,) the path's curvature averaged over
            ``curvature_window``, as the speed profile reads it [1/m].
    """

    def __init__(self, path: GlobalPath, config: SpeedProfileConfig) -> None:
        pts = np.asarray(path.xy, dtype=float)
        self.line = path.polyline
        self.closed = path.closed
        self.length = self.line.end_station
        self.points: FloatArray = self.line.ring
        self.stations: FloatArray = self.line.stations
        if self.closed:
            laps = np.vstack([pts, pts, pts, pts[:1]])
            free = dataclasses.replace(config, horizon_stop=False)
            v = speed_profile(laps, free)
            n = len(pts)
            k = profile_curvature(laps, config)
            self.speeds: FloatArray = np.append(v[n : 2 * n], v[n])
            self.curvature: FloatArray = np.append(k[n : 2 * n], k[n])
        else:
            self.speeds = speed_profile(pts, dataclasses.replace(config, horizon_stop=True))
            self.curvature = profile_curvature(pts, config)

    def speed_at(self, station: float) -> float:
        """Allowed speed at arc length ``station`` [m] along the global path [m/s]."""
        return float(self.line.interpolate(self.speeds, station))

    def speeds_at(self, stations: FloatArray) -> FloatArray:
        """Allowed speeds (n,) [m/s] at arc lengths ``stations`` (n,) [m]."""
        return self.line.interpolate(self.speeds, stations)

    def curvature_at(self, stations: FloatArray) -> FloatArray:
        """Curvature (n,) [1/m] at arc lengths ``stations`` (n,) [m]."""
        return self.line.interpolate(self.curvature, stations)

    def points_at(self, stations: FloatArray) -> FloatArray:
        """Points (n, 2) [m] in ``reference`` at arc lengths ``stations`` (n,) [m]
        (a loop's wrap around; an open path's end holds beyond it)."""
        return self.line.at(stations)
