"""The env's observation: the estimated ego state and the K nearest detected cones.

Vector mode (float32, shape ``(6 + 3 K,)``)::

    [speed, yaw_rate, steer_cmd, accel_cmd, pos_std, yaw_std,
     x_1, y_1, m_1, ..., x_K, y_K, m_K]

* ``speed`` [m/s] and ``yaw_rate`` [rad/s]: the EKF estimate in ``fused`` mode,
  otherwise the last wheel-speed and gyro messages (what the car measures);
* ``steer_cmd``, ``accel_cmd``: the previous action, in [-1, 1];
* ``pos_std`` [m], ``yaw_std`` [rad]: the EKF's 1-sigma uncertainty, the
  position's radial sqrt(sigma_x^2 + sigma_y^2) and the heading's (0 when no
  filter runs: ``truth`` is exact, ``raw`` states none; their upper bounds,
  1000 m and pi, while the filter has no estimate yet);
* ``x_i, y_i`` [m]: the latest cone detection in ``os_sensor``, nearest first
  (the ROS pipeline's ``/sorted_cones_time``), ``m_i`` = 1 for a real entry and 0 for
  padding (padded entries are zero).

Dict mode adds the colours (one-hot over ``CONE_COLOURS``), the pose of
``gps_antenna`` in ``reference`` with its 3x3 covariance, and ``pose_valid``:
in ``fused`` mode the EKF's estimate now and its covariance; in ``raw`` and
``truth`` mode the pose the frame tree holds (the broadcaster's last
``reference -> gps_antenna``) with a zero covariance. ``pose_valid`` is 1 when
there is a pose, 0 before the first one (the filter not yet initialised, no
broadcast yet), when ``pose`` and ``pose_covariance`` are zeros.
``cones_age`` [s] is how old the cone detection is: the simulation time now
minus its stamp (the scan's capture time), so the detector's latency (rtk:
0.2 s, fssim's LiDAR) plus the time since it arrived; ``AGE_BOUND`` (1000 s)
before the first detection. A policy that drives on the cones can read from
it how far the car has moved since they were seen. Every value
is clipped into the space's bounds so ``observation_space.contains(obs)``
always holds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from conesim.core.messages import CONE_COLOURS, ConeDetections, Imu, Message, WheelSpeed
from conesim.core.pose import Pose2D
from conesim.localization.ekf import Estimate

EGO_SIZE = 6
EGO_LOW = np.array([-5.0, -10.0, -1.0, -1.0, 0.0, 0.0], dtype=np.float32)
EGO_HIGH = np.array([60.0, 10.0, 1.0, 1.0, 1e3, math.pi], dtype=np.float32)
CONE_BOUND = 100.0  # [m] beyond any detector's range
POSE_BOUND = 1e5  # [m]
AGE_BOUND = 1e3  # [s] the detection's age before there is one


def observation_space(max_cones: int, mode: str) -> spaces.Space[Any]:
    """The Box (vector) or Dict (dict) observation space."""
    cone_low = np.tile(np.array([-CONE_BOUND, -CONE_BOUND, 0.0], np.float32), max_cones)
    cone_high = np.tile(np.array([CONE_BOUND, CONE_BOUND, 1.0], np.float32), max_cones)
    if mode == "vector":
        return spaces.Box(
            np.concatenate([EGO_LOW, cone_low]),
            np.concatenate([EGO_HIGH, cone_high]),
            dtype=np.float32,
        )
    return spaces.Dict(
        {
            "ego": spaces.Box(EGO_LOW, EGO_HIGH, dtype=np.float32),
            "cones": spaces.Box(-CONE_BOUND, CONE_BOUND, (max_cones, 2), dtype=np.float32),
            "cone_mask": spaces.Box(0.0, 1.0, (max_cones,), dtype=np.float32),
            "cone_colours": spaces.Box(0.0, 1.0, (max_cones, len(CONE_COLOURS)), dtype=np.float32),
            "pose": spaces.Box(
                np.array([-POSE_BOUND, -POSE_BOUND, -math.pi], np.float32),
                np.array([POSE_BOUND, POSE_BOUND, math.pi], np.float32),
                dtype=np.float32,
            ),
            "pose_covariance": spaces.Box(-1e6, 1e6, (3, 3), dtype=np.float32),
            "pose_valid": spaces.Box(0.0, 1.0, (1,), dtype=np.float32),
            "cones_age": spaces.Box(0.0, AGE_BOUND, (1,), dtype=np.float32),
        }
    )


@dataclass
class SensorMemory:
    """The latest message of each kind the observation is built from."""

    detections: ConeDetections | None = None
    wheel_speed: float = 0.0
    yaw_rate: float = 0.0
    # The cone part of the observation, built once per detection (the
    # detector runs at 10 Hz, the env observes at 50 Hz): the detection and
    # max_cones it was built for, then (cones, mask, colours, flat).
    _cone_block: tuple[Any, ...] | None = field(default=None, repr=False, compare=False)

    def update(self, messages: list[Message]) -> None:
        """Keep the newest detection, wheel speed and gyro reading (finite ones)."""
        for msg in messages:
            if isinstance(msg, ConeDetections):
                self.detections = msg
            elif isinstance(msg, WheelSpeed) and math.isfinite(msg.speed):
                self.wheel_speed = msg.speed
            elif isinstance(msg, Imu) and math.isfinite(msg.yaw_rate):
                self.yaw_rate = msg.yaw_rate

    def cone_block(
        self, max_cones: int
    ) -> tuple[NDArray[np.float32], NDArray[np.float32], NDArray[np.float32], NDArray[np.float32]]:
        """(cones, mask, colours, flat [x, y, m] * K) of the latest detection.

        Built once per detection and kept; callers copy what they hand out.
        """
        det = self.detections
        block = self._cone_block
        if block is not None and block[0] is det and block[1] == max_cones:
            return block[2], block[3], block[4], block[5]
        cones = np.zeros((max_cones, 2), dtype=np.float32)
        mask = np.zeros(max_cones, dtype=np.float32)
        colours = np.zeros((max_cones, len(CONE_COLOURS)), dtype=np.float32)
        if det is not None and len(det):
            pts = np.asarray(det.points[:, :2], dtype=float)
            finite = np.all(np.isfinite(pts), axis=1)
            rows = np.flatnonzero(finite)[:max_cones]
            n = len(rows)
            cones[:n] = np.clip(pts[rows], -CONE_BOUND, CONE_BOUND)
            mask[:n] = 1.0
            if det.colours is not None:
                for k, row in enumerate(rows):
                    colours[k, CONE_COLOURS.index(det.colours[row])] = 1.0
        flat = np.column_stack([cones, mask]).ravel()
        self._cone_block = (det, max_cones, cones, mask, colours, flat)
        return cones, mask, colours, flat


def build_observation(
    memory: SensorMemory,
    estimate: Estimate | None,
    action: NDArray[np.float32],
    max_cones: int,
    mode: str,
    *,
    published: Pose2D | None = None,
    awaiting_estimate: bool = False,
    now: float,
) -> NDArray[np.float32] | dict[str, NDArray[np.float32]]:
    """The observation for the current step (see the module docstring).

    ``published`` is the frame tree's pose, used in dict mode when there is
    no ``estimate`` (``raw`` and ``truth`` localization).
    ``awaiting_estimate``: a filter runs but has no estimate yet, so the
    uncertainties are their upper bounds, not the 0 of "no filter".
    ``now``: the simulation time [s], for the detection's age in dict mode.
    """
    if estimate is None and awaiting_estimate:
        speed, yaw_rate = memory.wheel_speed, memory.yaw_rate
        pos_std, yaw_std = float(EGO_HIGH[4]), float(EGO_HIGH[5])
    elif estimate is not None:
        speed, yaw_rate = estimate.speed, estimate.yaw_rate
        cov = estimate.pose_covariance
        pos_std = math.sqrt(max(0.0, float(cov[0, 0] + cov[1, 1])))
        yaw_std = math.sqrt(max(0.0, float(cov[2, 2])))
    else:
        speed, yaw_rate, pos_std, yaw_std = memory.wheel_speed, memory.yaw_rate, 0.0, 0.0
    ego = np.minimum(
        np.maximum(
            np.array([speed, yaw_rate, action[0], action[1], pos_std, yaw_std], dtype=np.float32),
            EGO_LOW,
        ),
        EGO_HIGH,
    )  # np.clip's values, without its wrapper's cost
    cones, mask, colours, flat = memory.cone_block(max_cones)
    if mode == "vector":
        out = np.empty(EGO_SIZE + flat.size, dtype=np.float32)
        out[:EGO_SIZE] = ego
        out[EGO_SIZE:] = flat
        return out
    cones, mask, colours = cones.copy(), mask.copy(), colours.copy()
    pose_cov = np.zeros((3, 3), dtype=np.float32)
    if estimate is not None:
        at: Pose2D | None = estimate.pose
        pose_cov = np.asarray(estimate.pose_covariance, dtype=np.float32)
    else:
        at = published
    xyz = (0.0, 0.0, 0.0) if at is None else (at.x, at.y, at.yaw)
    det = memory.detections
    age = AGE_BOUND if det is None else now - det.header.stamp
    age = min(max(age, 0.0), AGE_BOUND) if math.isfinite(age) else AGE_BOUND
    pose = np.array(xyz, dtype=np.float32)
    return {
        "ego": ego,
        "cones": cones,
        "cone_mask": mask,
        "cone_colours": colours,
        "pose": np.clip(
            pose, [-POSE_BOUND, -POSE_BOUND, -math.pi], [POSE_BOUND, POSE_BOUND, math.pi]
        ).astype(np.float32),
        "pose_covariance": np.clip(pose_cov, -1e6, 1e6).astype(np.float32),
        "pose_valid": np.array([0.0 if at is None else 1.0], dtype=np.float32),
        "cones_age": np.array([age], dtype=np.float32),
    }
