"""The env's observation: the ego state, the K nearest detected cones, the path ahead.

Vector mode (the default): float32, shape ``(8 + 5 K,)``, every entry
scaled to order 1 and clipped to the space's bounds::

    [speed, yaw_rate, steer, accel, pose_valid, pos_std, yaw_std, cones_age,
     x_1, y_1, m_1, side_1, orange_1, ..., x_K, y_K, m_K, side_K, orange_K,
     px_1, py_1, ..., px_N, py_N]

(the last ``2 N`` entries only with ``path_preview`` N > 0; shape ``(8 + 5 K + 2 N,)``)

============  ===========================================  =========  ==========
entry         what                                         scale      bounds
============  ===========================================  =========  ==========
speed         estimated forward speed                      20 m/s     [-1, 2]
yaw_rate      estimated yaw rate                           2 rad/s    [-2, 2]
steer, accel  the previous command (below)                 (below)    [-1, 1]
pose_valid    1 once localization has a pose, else 0       -          {0, 1}
pos_std       EKF 1-sigma position, sqrt(sx^2 + sy^2)      1 m        [0, 3]
yaw_std       EKF 1-sigma heading                          0.1 rad    [0, 3]
cones_age     now minus the detection's capture stamp      1 s        [0, 1]
x_i, y_i      detected cone in ``os_sensor``, nearest 1st  max_range  [-1, 1]
m_i           1 for a detected cone, 0 for padding         -          {0, 1}
side_i        +1 blue (left), -1 yellow (right), else 0    -          {-1, 0, 1}
orange_i      1 for an orange or big orange cone           -          {0, 1}
px_j, py_j    global path point j ahead, ``gps_antenna``   N x step   [-2, 2]
============  ===========================================  =========  ==========

Each entry is its value divided by its scale, then clipped to its bounds.

* speed and yaw rate are the EKF's estimate in ``fused`` mode once it has
  one, otherwise the last wheel-speed and gyro messages (what the car
  measures);
* steer and accel: the commanded steering over ``max_steer`` and
  acceleration over the action's acceleration scale (``max_accel`` for the
  centred action, ``max_decel`` for the physical one), so the centred
  action reads back as itself;
* ``pose_valid`` is 0 before localization has a pose (the filter not yet
  initialised, or no broadcast yet); ``pos_std`` and ``yaw_std`` are then 0,
  as they are where no filter runs (``truth`` is exact, ``raw`` states none);
* ``max_range`` is the cone detector's (rtk: 15 m); padded cones are zeros;
  a colour-blind detection or an ``unknown`` cone has side and orange 0;
  ``cones_age`` is 1 before the first detection.
* the path preview (``path_preview`` N points, ``path_preview_step`` apart):
  the track's global path (the asset the autopilot plans with, surveyed as
  the scenario says) at N stations ``step``, ``2 step``, ... ahead of the
  antenna's projection on it, in the frame of the localized pose (the
  estimate, or the frame tree's pose without a filter): x forward, y left,
  over the preview's length ``N step`` (at most 100 m). It is zeros while
  ``pose_valid`` is 0. A policy reads the road ahead from it, not from the
  cones of the last scan alone (f1tenth_gym and CarRacing policies get a
  comparable look ahead: waypoints or the picture).

Dict mode (raw units, as before the vector mode was normalised): ``ego`` is
``[speed, yaw_rate, steer_cmd, accel_cmd, pos_std, yaw_std]`` [m/s, rad/s,
-, -, m, rad], the uncertainties at their upper bounds (1000 m, pi) while
the filter has no estimate yet; ``cones`` (K, 2) [m] in ``os_sensor`` with
``cone_mask``, the colours (one-hot over ``CONE_COLOURS``), the pose of
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
it how far the car has moved since they were seen. With a path preview, ``path`` holds its
points, (N, 2) [m] in ``gps_antenna`` (zeros without a pose). Every value
is clipped into the space's bounds so ``observation_space.contains(obs)``
always holds.

The preview's projection is race control's walk along the path
(``sim.progress.PolylineProgress``), so a figure of eight's crossing does
not make it jump to the other loop; more than 2 m off the path, a stretch a
whole-path search finds 1 m nearer takes over (as race control's does off
the track), so a car that left the path and rejoined it elsewhere sees the
road ahead of it there. The first projection of an episode has no walk to
go on: started on a crossing (a start pose on the skidpad's middle), it may
take either loop.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from conesim.core.messages import CONE_COLOURS, ConeDetections, Imu, Message, WheelSpeed
from conesim.core.polyline import Polyline
from conesim.core.pose import Pose2D
from conesim.localization.ekf import Estimate
from conesim.sim.progress import PolylineProgress

EGO_LOW = np.array([-5.0, -10.0, -1.0, -1.0, 0.0, 0.0], dtype=np.float32)
EGO_HIGH = np.array([60.0, 10.0, 1.0, 1.0, 1e3, math.pi], dtype=np.float32)
CONE_BOUND = 100.0  # [m] beyond any detector's range
POSE_BOUND = 1e5  # [m]
AGE_BOUND = 1e3  # [s] the detection's age before there is one


# Vector mode: the ego entries' scales and bounds (see the module docstring).
VECTOR_EGO_SIZE = 8
VECTOR_CONE_SIZE = 5
SPEED_SCALE = 20.0  # [m/s]
YAW_RATE_SCALE = 2.0  # [rad/s]
POS_STD_SCALE = 1.0  # [m]
YAW_STD_SCALE = 0.1  # [rad]
AGE_SCALE = 1.0  # [s]
VECTOR_EGO_LOW = np.array([-1.0, -2.0, -1.0, -1.0, 0.0, 0.0, 0.0, 0.0], dtype=np.float32)
VECTOR_EGO_HIGH = np.array([2.0, 2.0, 1.0, 1.0, 1.0, 3.0, 3.0, 1.0], dtype=np.float32)
_EGO_LOW = VECTOR_EGO_LOW.tolist()
_EGO_HIGH = VECTOR_EGO_HIGH.tolist()
PREVIEW_BOUND = 2.0  # vector mode: the preview's points over its length, clipped to +-this
PREVIEW_REJOIN_OFFSET = 2.0  # [m] farther than this from the path, the preview looks for a
PREVIEW_REJOIN_MARGIN = 1.0  # [m] stretch this much nearer (race control's rule, off the track)
_SIDE = {"blue": 1.0, "yellow": -1.0}
_ORANGE = {"orange": 1.0, "big_orange": 1.0}


def observation_space(max_cones: int, mode: str, preview: int = 0) -> spaces.Space[Any]:
    """The Box (vector) or Dict (dict) observation space (``preview``: path points)."""
    if mode == "vector":
        cone_low = np.tile(np.array([-1.0, -1.0, 0.0, -1.0, 0.0], np.float32), max_cones)
        cone_high = np.tile(np.array([1.0, 1.0, 1.0, 1.0, 1.0], np.float32), max_cones)
        path = np.full(2 * preview, PREVIEW_BOUND, np.float32)
        return spaces.Box(
            np.concatenate([VECTOR_EGO_LOW, cone_low, -path]),
            np.concatenate([VECTOR_EGO_HIGH, cone_high, path]),
            dtype=np.float32,
        )
    path_space = {"path": spaces.Box(-CONE_BOUND, CONE_BOUND, (preview, 2), np.float32)}
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
            **(path_space if preview else {}),
        }
    )


class PathPreview:
    """The global path ahead of a pose: ``points`` points ``step`` [m] apart
    along it from the pose's nearest point, in the pose's frame.

    Args:
        path: the global path in ``reference`` (``GlobalPath.polyline``).
        points: N [-].
        step: their spacing along the path [m].

    Attributes:
        length: how far ahead the last point is, ``N step`` [m] (vector
            mode's scale).
    """

    def __init__(self, path: Polyline, points: int, step: float) -> None:
        self._line = path
        self._progress = PolylineProgress(path)
        self._ahead = step * np.arange(1, points + 1, dtype=float)
        self.length = float(self._ahead[-1])

    def points(self, pose: Pose2D) -> NDArray[np.float64]:
        """(N, 2) [m]: the points in ``pose``'s frame (x forward, y left)."""
        walked = self._progress.project_xy(pose.x, pose.y)
        if abs(walked[1]) > PREVIEW_REJOIN_OFFSET:  # off the path: rejoined elsewhere?
            walked = self._progress.nearer_stretch(pose.x, pose.y, walked, PREVIEW_REJOIN_MARGIN)
        return pose.inverse_transform_points(self._line.at(walked[0] + self._ahead))


@dataclass
class SensorMemory:
    """The latest message of each kind the observation is built from."""

    detections: ConeDetections | None = None
    wheel_speed: float = 0.0
    yaw_rate: float = 0.0
    # The cone part of the observation, built once per detection (the
    # detector runs at 10 Hz, the env observes at 50 Hz): the detection and
    # max_cones it was built for, then (cones, mask, colours).
    _cone_block: tuple[Any, ...] | None = field(default=None, repr=False, compare=False)
    # Vector mode's cone entries, likewise: (detection, max_cones, range, flat).
    _vector_block: tuple[Any, ...] | None = field(default=None, repr=False, compare=False)

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
    ) -> tuple[NDArray[np.float32], NDArray[np.float32], NDArray[np.float32]]:
        """(cones, mask, colours) of the latest detection, dict mode's raw units.

        Built once per detection and kept; callers copy what they hand out.
        """
        det = self.detections
        block = self._cone_block
        if block is not None and block[0] is det and block[1] == max_cones:
            return block[2], block[3], block[4]
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
        self._cone_block = (det, max_cones, cones, mask, colours)
        return cones, mask, colours

    def vector_cones(self, max_cones: int, max_range: float) -> NDArray[np.float32]:
        """Vector mode's cone entries ``[x, y, m, side, orange] * K`` (module docstring).

        Built once per detection and kept; the caller copies it into the observation.
        """
        det = self.detections
        block = self._vector_block
        if block is not None and block[0] is det and block[1:3] == (max_cones, max_range):
            flat: NDArray[np.float32] = block[3]
            return flat
        out = np.zeros((max_cones, VECTOR_CONE_SIZE), dtype=np.float32)
        if det is not None and len(det):
            pts = np.asarray(det.points[:, :2], dtype=float)
            rows = np.flatnonzero(np.all(np.isfinite(pts), axis=1))[:max_cones]
            n = len(rows)
            out[:n, :2] = np.clip(pts[rows] / max_range, -1.0, 1.0)
            out[:n, 2] = 1.0
            if det.colours is not None:
                colours = [det.colours[row] for row in rows]
                out[:n, 3] = [_SIDE.get(c, 0.0) for c in colours]
                out[:n, 4] = [_ORANGE.get(c, 0.0) for c in colours]
        flat = out.ravel()
        self._vector_block = (det, max_cones, max_range, flat)
        return flat


def _motion(memory: SensorMemory, estimate: Estimate | None) -> tuple[float, float, float, float]:
    """(speed [m/s], yaw rate [rad/s], 1-sigma position [m] and heading [rad]):
    the estimate's, or without one the last messages' with no uncertainty."""
    if estimate is None:
        return memory.wheel_speed, memory.yaw_rate, 0.0, 0.0
    cov = estimate.pose_covariance
    pos_std = math.sqrt(max(0.0, float(cov[0, 0] + cov[1, 1])))
    yaw_std = math.sqrt(max(0.0, float(cov[2, 2])))
    return estimate.speed, estimate.yaw_rate, pos_std, yaw_std


def build_vector(
    memory: SensorMemory,
    estimate: Estimate | None,
    command: tuple[float, float],
    max_cones: int,
    max_range: float,
    *,
    pose_valid: bool,
    now: float,
    preview: tuple[NDArray[np.float64], float] | None = None,
) -> NDArray[np.float32]:
    """The normalised vector observation (see the module docstring).

    Args:
        memory: the latest messages.
        estimate: the EKF's estimate now, or None (no filter, or not yet).
        command: the previous command over the action's scales [-].
        max_cones: K.
        max_range: the cone detector's range, the cones' scale [m].
        pose_valid: localization has a pose.
        now: the simulation time [s].
        preview: with a path preview, (its points in ``gps_antenna`` [m], zeros
            without a pose; its length [m], their scale).
    """
    speed, yaw_rate, pos_std, yaw_std = _motion(memory, estimate)
    det = memory.detections
    age = 1.0 if det is None else (now - det.header.stamp) / AGE_SCALE
    ego = (
        speed / SPEED_SCALE,
        yaw_rate / YAW_RATE_SCALE,
        command[0],
        command[1],
        1.0 if pose_valid else 0.0,
        pos_std / POS_STD_SCALE,
        yaw_std / YAW_STD_SCALE,
        age if math.isfinite(age) else 1.0,
    )
    cones = VECTOR_EGO_SIZE + VECTOR_CONE_SIZE * max_cones
    out = np.empty(cones + (0 if preview is None else preview[0].size), np.float32)
    # clipped as plain floats: np.clip's wrapper costs more than the rest
    out[:VECTOR_EGO_SIZE] = [
        min(max(v, lo), hi) for v, lo, hi in zip(ego, _EGO_LOW, _EGO_HIGH, strict=True)
    ]
    out[VECTOR_EGO_SIZE:cones] = memory.vector_cones(max_cones, max_range)
    if preview is not None:
        scaled = preview[0].ravel() / preview[1]  # clipped below: np.clip's wrapper costs more
        out[cones:] = np.minimum(np.maximum(scaled, -PREVIEW_BOUND), PREVIEW_BOUND)
    return out


def build_dict(
    memory: SensorMemory,
    estimate: Estimate | None,
    command: tuple[float, float],
    max_cones: int,
    *,
    published: Pose2D | None = None,
    awaiting_estimate: bool = False,
    now: float,
    preview: NDArray[np.float64] | None = None,
) -> dict[str, NDArray[np.float32]]:
    """The dict observation for the current step (see the module docstring).

    ``command``: the previous command over the action's scales.
    ``preview``: the path preview's points in ``gps_antenna`` [m] (zeros
    without a pose), or None without a preview.
    ``published`` is the frame tree's pose, used when there is no
    ``estimate`` (``raw`` and ``truth`` localization).
    ``awaiting_estimate``: a filter runs but has no estimate yet, so the
    uncertainties are their upper bounds, not the 0 of "no filter".
    ``now``: the simulation time [s], for the detection's age.
    """
    speed, yaw_rate, pos_std, yaw_std = _motion(memory, estimate)
    if estimate is None and awaiting_estimate:
        pos_std, yaw_std = float(EGO_HIGH[4]), float(EGO_HIGH[5])
    ego = np.clip(
        np.array([speed, yaw_rate, command[0], command[1], pos_std, yaw_std], dtype=np.float32),
        EGO_LOW,
        EGO_HIGH,
    )
    cones, mask, colours = memory.cone_block(max_cones)
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
        **(
            {}
            if preview is None
            else {"path": np.clip(preview, -CONE_BOUND, CONE_BOUND).astype(np.float32)}
        ),
    }
