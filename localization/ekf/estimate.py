"""The fusion EKF's output: the pose of ``gps_antenna`` in ``reference`` with its covariance."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from conesim.core.pose import Pose2D, wrap_angle
from conesim.localization.ekf.model import VX, VY, YAW, X, wrap_yaw

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class Estimate:
    """The filter's estimate at one time.

    Attributes:
        stamp: time of the estimate [s].
        pose: ``gps_antenna`` in ``reference``: x, y [m], yaw [rad] in [-pi, pi).
        speed: forward speed of the antenna, vx [m/s].
        lateral_speed: leftward speed of the antenna, vy [m/s].
        yaw_rate: the last gyro sample minus the estimated bias [rad/s].
        pose_covariance: covariance of (x, y, yaw), (3, 3) [m^2, m rad, rad^2].
        covariance: covariance of the whole state, (n, n) (with ``slam``, of the
            vehicle's states: the map is ``FusionEkf.landmark_state()``).
        state: the whole state, (n,) (order: ``names``; the vehicle's with ``slam``).
        names: state names (``localization.ekf.model``).
    """

    stamp: float
    pose: Pose2D
    speed: float
    lateral_speed: float
    yaw_rate: float
    pose_covariance: FloatArray
    covariance: FloatArray
    state: FloatArray
    names: tuple[str, ...]

    @classmethod
    def from_state(
        cls,
        stamp: float,
        x: FloatArray,
        p: FloatArray,
        yaw_rate: float,
        names: tuple[str, ...],
        *,
        copy: bool = True,
    ) -> Estimate:
        """Build from a state (n, 1) and covariance (n, n), held read-only.

        Args:
            copy: copy the arrays (default). False shares them (``state`` a view
                of ``x``) and makes them read-only: for float64 arrays that are
                read-only already or that no one else holds (the filter's).
        """
        if copy:
            state = np.array(x, dtype=float).reshape(-1)
            cov = np.array(p, dtype=float)
        else:
            x.flags.writeable = False
            state = x.reshape(-1)
            cov = p
        pose_cov = cov[X : YAW + 1, X : YAW + 1].copy()
        for a in (state, cov, pose_cov):
            a.flags.writeable = False
        values = state.tolist()  # floats: cheaper than numpy scalars
        return cls(
            stamp=stamp,
            pose=Pose2D(values[X], values[X + 1], wrap_yaw(values[YAW])),
            speed=values[VX],
            lateral_speed=values[VY],
            yaw_rate=yaw_rate,
            pose_covariance=pose_cov,
            covariance=cov,
            state=state,
            names=names,
        )

    def pose_error(self, truth: Pose2D) -> FloatArray:
        """Estimate minus truth: (dx [m], dy [m], dyaw [rad] wrapped), (3,)."""
        return np.array(
            [
                self.pose.x - truth.x,
                self.pose.y - truth.y,
                float(wrap_angle(self.pose.yaw - truth.yaw)),
            ]
        )

    def nees(self, truth: Pose2D) -> float:
        """Normalised estimation error squared of the pose, e' P^-1 e (chi2 with 3 dof)."""
        e = self.pose_error(truth)
        return float(e @ np.linalg.solve(self.pose_covariance, e))
