"""Synthetic tracks and scenes with known geometry, shared by the planner tests.

A track is a dense centreline in ``reference`` plus cones at +-width/2 along
its normal every ``spacing`` of arc length (left = + normal). A scene puts the
car at a known pose in a frame tree and returns the cones in view as a
``ConeDetections`` in ``os_sensor``: the cones of a synthetic track pushed
through a known pose. Nothing here uses ``tracks`` or ``sim``.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from types import ModuleType

import numpy as np
import pytest
from numpy.typing import NDArray

from conesim.core.messages import ConeDetections, Header
from conesim.core.pose import Pose2D
from conesim.localization.frames import Buffer, TransformStamped
from conesim.tracks.global_path import GlobalPath, global_path_from_centreline

FloatArray = NDArray[np.float64]
SENSOR_Z = -0.1  # [m] os_sensor below gps_antenna (seed)


@dataclass(frozen=True)
class SyntheticTrack:
    """A track with known centreline and boundaries.

    Attributes:
        centre: (n, 2) dense centreline [m], in driving order.
        closed: whether the centreline is a loop.
        width: track width [m].
        left: (a, 2) left cones [m].
        right: (b, 2) right cones [m].
    """

    centre: FloatArray
    closed: bool
    width: float
    left: FloatArray
    right: FloatArray

    @property
    def global_path(self) -> GlobalPath:
        """The centreline as the global path."""
        return global_path_from_centreline(self.centre, closed=self.closed)

    def distance_to_centre(self, points: FloatArray) -> FloatArray:
        """(m,) distance of each point to the centreline polyline [m] (brute force)."""
        c = np.vstack([self.centre, self.centre[:1]]) if self.closed else self.centre
        a, d = c[:-1], np.diff(c, axis=0)
        rel = points[:, None, :] - a[None]
        t = np.clip(np.einsum("mki,ki->mk", rel, d) / np.einsum("ki,ki->k", d, d), 0.0, 1.0)
        gap = rel - t[..., None] * d[None]
        return np.sqrt(np.min(np.einsum("mki,mki->mk", gap, gap), axis=1))


def _normals(centre: FloatArray, closed: bool) -> FloatArray:
    if closed:
        nxt, prv = np.roll(centre, -1, axis=0), np.roll(centre, 1, axis=0)
    else:
        nxt = np.vstack([centre[1:], 2 * centre[-1:] - centre[-2:-1]])
        prv = np.vstack([2 * centre[:1] - centre[1:2], centre[:-1]])
    t = nxt - prv
    t /= np.hypot(t[:, 0], t[:, 1])[:, None]
    return np.column_stack([-t[:, 1], t[:, 0]])


def build_track(
    centre: FloatArray, closed: bool, width: float, spacing: float, phase: float = 0.0
) -> SyntheticTrack:
    """Cones at +-width/2 every ``spacing`` [m] of centreline arc length (aligned pairs)."""
    normals = _normals(centre, closed)
    ring = np.vstack([centre, centre[:1]]) if closed else centre
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(ring, axis=0).T))])
    total = s[-1]
    count = round(total / spacing) if closed else math.floor(total / spacing) + 1
    stations = phase + np.arange(count) * (total / count if closed else spacing)
    ring_n = np.vstack([normals, normals[:1]]) if closed else normals
    at = np.column_stack([np.interp(stations, s, ring[:, k]) for k in range(2)])
    n = np.column_stack([np.interp(stations, s, ring_n[:, k]) for k in range(2)])
    n /= np.hypot(n[:, 0], n[:, 1])[:, None]
    half = 0.5 * width
    return SyntheticTrack(centre, closed, width, at + half * n, at - half * n)


def straight_track(
    length: float = 80.0, width: float = 3.0, spacing: float = 5.0
) -> SyntheticTrack:
    """A straight along +x from (-10, 0), open."""
    x = np.arange(-10.0, length - 10.0 + 1e-9, 0.5)
    return build_track(np.column_stack([x, np.zeros_like(x)]), False, width, spacing)


def circle_track(
    radius: float = 15.0, width: float = 3.0, spacing: float = 5.0, clockwise: bool = False
) -> SyntheticTrack:
    """A circle about the origin, counter-clockwise from (radius, 0) unless ``clockwise``."""
    count = 720
    a = np.arange(count) * 2 * math.pi / count
    a = -a if clockwise else a
    centre = radius * np.column_stack([np.cos(a), np.sin(a)])
    return build_track(centre, True, width, spacing)


def hairpin_track(
    radius: float = 3.5, width: float = 3.0, spacing: float = 3.0, leg: float = 30.0
) -> SyntheticTrack:
    """Along +x at y = 0 to x = 0, a left U-turn about (0, radius), back along -x.

    The legs are 2 * radius apart; with the defaults the outside diameter is
    2 * (radius + width / 2) = 10 m (FS rules: >= 9 m) and the infield between
    the legs' inner rows is 2 * radius - width = 4 m wide.
    """
    step = 0.25
    x_in = np.arange(-leg, 0.0, step)
    a = np.arange(-math.pi / 2, math.pi / 2, step / radius)
    entry = np.column_stack([x_in, np.zeros_like(x_in)])
    turn = np.column_stack([radius * np.cos(a), radius + radius * np.sin(a)])
    x_out = -np.arange(0.0, leg, step)
    exit_ = np.column_stack([x_out, np.full(len(x_out), 2 * radius)])
    return build_track(np.vstack([entry, turn, exit_]), False, width, spacing)


@dataclass(frozen=True)
class Scene:
    """The car at a pose on a track, with its frame tree and detection.

    Attributes:
        track: the track.
        pose: ``gps_antenna`` in ``reference``.
        buffer: the frame tree holding the pose at ``stamp`` (and the static sensor link).
        detections: the cones in view, ``os_sensor``, nearest first.
        stamp: the capture time [s].
    """

    track: SyntheticTrack
    pose: Pose2D
    buffer: Buffer
    detections: ConeDetections
    stamp: float


def set_pose(buffer: Buffer, pose: Pose2D, stamp: float) -> None:
    """Put ``gps_antenna`` at ``pose`` at ``stamp`` (and the static sensor link once)."""
    buffer.set_transform(TransformStamped.from_pose2d("reference", "gps_antenna", stamp, pose))
    if not buffer.frame_exists("os_sensor"):
        buffer.set_transform_static(
            TransformStamped("gps_antenna", "os_sensor", 0.0, translation=(0.0, 0.0, SENSOR_Z))
        )


def detect(
    cones: FloatArray,
    pose: Pose2D,
    stamp: float,
    max_range: float = 20.0,
    colours: tuple[str, ...] | None = None,
) -> ConeDetections:
    """Ideal detections of ``cones`` (reference) seen from ``pose``, within ``max_range``."""
    local = pose.inverse_transform_points(cones)
    dist = np.hypot(local[:, 0], local[:, 1])
    order = np.argsort(dist, kind="stable")
    order = order[dist[order] <= max_range]
    pts = np.column_stack([local[order], np.full(len(order), -SENSOR_Z)])
    labels = None if colours is None else tuple(colours[i] for i in order)
    return ConeDetections(Header(stamp, "os_sensor"), pts, labels)


def make_scene(
    track: SyntheticTrack,
    pose: Pose2D,
    *,
    stamp: float = 1.0,
    max_range: float = 20.0,
    left: FloatArray | None = None,
    right: FloatArray | None = None,
    extra: FloatArray | None = None,
    colours: bool = False,
) -> Scene:
    """A scene: ``left``/``right`` override the track's cones, ``extra`` adds false positives.

    With ``colours`` the detections carry blue (left), yellow (right) and
    orange (extra) labels.
    """
    left = track.left if left is None else left
    right = track.right if right is None else right
    extra = np.zeros((0, 2)) if extra is None else extra
    cones = np.vstack([left, right, extra])
    labels = ("blue",) * len(left) + ("yellow",) * len(right) + ("orange",) * len(extra)
    buffer = Buffer()
    set_pose(buffer, pose, stamp)
    det = detect(cones, pose, stamp, max_range, labels if colours else None)
    return Scene(track, pose, buffer, det, stamp)


def pose_on(track: SyntheticTrack, index: int, lateral: float = 0.0, dyaw: float = 0.0) -> Pose2D:
    """The antenna pose on the centreline point ``index``, heading along it."""
    c = track.centre
    nxt = c[(index + 1) % len(c)]
    t = nxt - c[index]
    yaw = math.atan2(t[1], t[0])
    n = np.array([-math.sin(yaw), math.cos(yaw)])
    p = c[index] + lateral * n
    return Pose2D(float(p[0]), float(p[1]), yaw + dyaw)


@pytest.fixture
def straight() -> SyntheticTrack:
    """An 80 m straight, 3 m wide, cones every 5 m."""
    return straight_track()


@pytest.fixture
def circle() -> SyntheticTrack:
    """A counter-clockwise circle of radius 15 m, 3 m wide, cones every 5 m."""
    return circle_track()


@pytest.fixture
def hairpin() -> SyntheticTrack:
    """A left hairpin, 10 m outside diameter, 3 m wide."""
    return hairpin_track()


@pytest.fixture
def synth() -> ModuleType:
    """These helpers as a namespace: ``synth.make_scene(...)``."""
    return sys.modules[__name__]
