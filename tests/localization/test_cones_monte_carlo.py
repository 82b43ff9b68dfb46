"""The cone updates' NIS inside its chi-square band: a synthetic Monte Carlo and closed loops.

Synthetic: 200 scans of the 10-cone lane, each from a prior drawn from the
filter's own covariance (0.3 m, 1 deg), the map surveyed with the 3 cm per
cone and the 2 cm offset the filter assumes, the detections with the
detector's range and bearing noise.
The sum of the NIS is chi2(sum of the dof): its mean per dof lies in
[chi2.ppf(0.025, D) / D, chi2.ppf(0.975, D) / D], for D = 4000 about
[0.957, 1.044], and about 95 % of the scans lie in their own 95 % band.
Closed loop: ``consumer`` sensors with the map on two shipped tracks, where
the world's errors are what the filter models only approximately.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import chi2

from conesim.core.pose import Pose2D
from conesim.envs.runner import run_scenario
from conesim.localization.cones import ConeUpdate, ConeUpdateConfig, LandmarkMap
from tests.localization.cone_helpers import (
    assert_closed_loop_nis,
    filter_at,
    in_sensor,
    lane_map,
    noisy,
    scan,
)

RUNS = 200
SIGMA_XY = 0.3  # [m]
SIGMA_YAW = math.radians(1.0)  # [rad]


def test_nis_of_cone_updates_in_its_chi_square_band() -> None:
    """Mean NIS per dof of 200 synthetic scans inside the chi2(D) / D band; >= 90 % of
    the scans inside their own 95 % band."""
    rng = np.random.default_rng(0)
    cfg = ConeUpdateConfig()
    truth_map = lane_map()
    nis, dof, inside = 0.0, 0, 0
    for _ in range(RUNS):
        offset = cfg.map_bias_sigma * rng.standard_normal(2)
        surveyed = truth_map.positions + offset + cfg.map_sigma * rng.standard_normal((10, 2))
        update = ConeUpdate(LandmarkMap(surveyed, ["unknown"] * 10), cfg)
        truth = Pose2D(*(rng.standard_normal(3) * [2.0, 2.0, 0.05]))
        err = rng.standard_normal(3) * [SIGMA_XY, SIGMA_XY, SIGMA_YAW]
        prior = Pose2D(truth.x + err[0], truth.y + err[1], truth.yaw + err[2])
        ekf = filter_at(prior, SIGMA_XY, SIGMA_YAW, update)
        points = noisy(in_sensor(truth, truth_map.positions), cfg, rng)
        result = ekf.process(scan(0.0, points))
        assert result is not None and result.accepted and result.nis is not None
        nis += result.nis
        dof += result.dof
        inside += chi2.ppf(0.025, result.dof) <= result.nis <= chi2.ppf(0.975, result.dof)
    assert dof >= 0.99 * RUNS * 20  # a detection beyond its 99.9 % gate is left out
    assert chi2.ppf(0.025, dof) / dof <= nis / dof <= chi2.ppf(0.975, dof) / dof
    assert inside / RUNS >= 0.9


@pytest.mark.slow
@pytest.mark.parametrize("track", ["autocross", "trackdrive"])
def test_closed_loop_cone_nis_near_one(track: str) -> None:
    """consumer GPS with the map, one lap: NIS per dof within 10 % of 1, >= 85 % of the
    scans in their band, the pose within 0.2 m and 0.5 deg (issue 16's targets)."""
    r = run_scenario(track, sensors="consumer", localization="cones", laps=1)
    assert_closed_loop_nis(r.cone_associations)
    assert r.clean
    assert r.localization_pos_rmse_m is not None and r.localization_pos_rmse_m <= 0.2
    assert r.localization_yaw_rmse_deg is not None and r.localization_yaw_rmse_deg <= 0.5
