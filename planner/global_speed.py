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

from localization.global_path import GlobalPath
from planner.config import SpeedProfileConfig
from planner.geometry import FloatArray, arc_length
from planner.speed_profile import speed_profile


class GlobalSpeedPlan:
    """Speeds along the global path.

    Args:
        path: the global path in ``reference``.
        config: the same limits as the local speed profile.
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
            self.stations: FloatArray = stations
            self.speeds: FloatArray = np.append(v[n : 2 * n], v[n])
        else:
            self.stations = arc_length(pts)
            self.length = float(self.stations[-1])
            self.speeds = speed_profile(pts, dataclasses.replace(config, horizon_stop=True))

    def speed_at(self, station: float) -> float:
        """Allowed speed at arc length ``station`` [m] along the global path [m/s]."""
        if self.closed:
            station %= self.length
        return float(np.interp(station, self.stations, self.speeds))

    def speeds_at(self, stations: FloatArray) -> FloatArray:
        """Allowed speeds (n,) [m/s] at arc lengths ``stations`` (n,) [m]."""
        st = np.asarray(stations, dtype=float)
        if self.closed:
            st = np.mod(st, self.length)
        return np.interp(st, self.stations, self.speeds)
