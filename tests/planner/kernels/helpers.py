"""Scenes and numpy references shared by the kernels' tests (and ``test_kernel_chains``).

Random cones on a wobbly track (``random_cones``), a wobbly loop's projector
(``loop_projector``), cone sets joined (``joined``) and their station gaps
(``station_gap``), and the numpy formulations of the pair table, the cones'
boundary offsets and the track estimate as they stood before the kernels
(``ref_pairs``, ``ref_boundary_offset``, ``ref_track``).

Each test's reference is the numpy formulation the kernel replaced (as it
stood before the kernels), compared exactly on random inputs that include
ties (points on a grid), zero-length steps and closed (wrapped) station
axes.
"""

from __future__ import annotations

import math

import numpy as np

from conesim.planner import MidlineConfig
from conesim.planner.bridges import (
    ConeSet,
    TrackEstimate,
)
from conesim.planner.geometry import IntArray, PathProjector, StationAxis
from conesim.tracks.global_path import global_path_from_centreline
from tests.planner.kernels.geometry_reference import axis_difference, station_difference


def ref_pairs(cones: ConeSet, config: MidlineConfig) -> tuple[np.ndarray, ...]:
    """``pair_table``'s arrays with numpy (distance everywhere)."""
    left = (cones.side > 0).nonzero()[0]
    right = (cones.side < 0).nonzero()[0]
    pl, pr = cones.points[left], cones.points[right]
    dist = np.hypot(np.subtract.outer(pl[:, 0], pr[:, 0]), np.subtract.outer(pl[:, 1], pr[:, 1]))
    gap = np.abs(
        station_difference(
            cones.station[right][None, :],
            cones.station[left][:, None],
            cones.axis.length,
            cones.axis.closed,
        )
    )
    ol, or_ = cones.offset[left], cones.offset[right]
    return (
        left,
        right,
        dist,
        gap <= config.max_station_gap,
        np.subtract.outer(ol, or_),
        0.5 * (np.add.outer(ol, or_)),
    )


def joined(first: ConeSet, then: ConeSet) -> ConeSet:
    """``first`` followed by ``then`` (``first`` itself when ``then`` is empty)."""
    if len(then) == 0:
        return first
    return ConeSet(
        points=np.concatenate([first.points, then.points]),
        side=np.concatenate([first.side, then.side]),
        offset=np.concatenate([first.offset, then.offset]),
        station=np.concatenate([first.station, then.station]),
        tangent=np.concatenate([first.tangent, then.tangent]),
        virtual=np.concatenate([first.virtual, then.virtual]),
        axis=first.axis,
    )


def station_gap(cones: ConeSet, i: IntArray, j: IntArray) -> np.ndarray:
    """|station[j] - station[i]|, wrapped on a closed path [m]."""
    return np.abs(axis_difference(cones.axis, cones.station[j], cones.station[i]))


def ref_boundary_offset(track: TrackEstimate, cones: ConeSet) -> np.ndarray:
    """``kernels.boundary_offset`` with numpy: ``side * (offset - centre) - width / 2``."""
    return cones.side * (cones.offset - track.centre) - 0.5 * track.width


def ref_track(cones: ConeSet, config: MidlineConfig) -> TrackEstimate:
    """``estimate_track`` with numpy masks, argmins and ``numpy.median``."""
    _, _, dist, same, span, middle = ref_pairs(cones, config)
    valid = (
        same
        & (span >= config.min_track_width)
        & (span <= config.max_track_width)
        & (dist <= config.max_bridge_length)
    )
    rows = np.nonzero(valid.any(axis=1))[0]
    cols = np.nonzero(valid.any(axis=0))[0]
    if len(rows) == 0 or len(rows) + len(cols) < config.min_width_samples:
        return TrackEstimate(config.nominal_track_width, 0.0, measured=False)
    masked = np.where(valid, dist, np.inf)
    width = valid.shape[1]
    picks = np.concatenate(
        [rows * width + masked.argmin(axis=1)[rows], masked.argmin(axis=0)[cols] * width + cols]
    )
    return TrackEstimate(
        float(np.median(span.take(picks))), float(np.median(middle.take(picks))), measured=True
    )


def random_cones(rng: np.random.Generator, n: int, closed: bool, grid: bool = False) -> ConeSet:
    """Cones on both sides of a wobbly track, some strays; optionally on a 0.5 m grid."""
    x = np.sort(rng.uniform(0.0, 40.0, n))
    side = np.where(rng.random(n) > 0.5, 1, -1).astype(np.int8)
    offset = side * rng.normal(1.75, 0.4, n)
    offset[rng.random(n) < 0.1] *= 0.2  # strays near the middle
    points = np.column_stack([x, offset + 0.3 * np.sin(x / 5.0)])
    if grid:
        points = np.round(points * 2.0) / 2.0
        offset = np.round(offset * 2.0) / 2.0
    station = (x + 50.0) % 60.0 if closed else x.copy()
    tangent = np.tile([1.0, 0.0], (n, 1))
    return ConeSet(
        points=points,
        side=side,
        offset=offset,
        station=station,
        tangent=tangent,
        virtual=np.zeros(n, dtype=bool),
        axis=StationAxis(60.0 if closed else 200.0, closed),
    )


def loop_projector(closed: bool, grid: bool = False) -> PathProjector:
    """A wobbly loop of 400 points (integer coordinates when ``grid``: exact ties)."""
    s = np.linspace(0.0, 2 * math.pi, 400, endpoint=False)
    xy = np.column_stack([30 * np.cos(s) + 3 * np.cos(7 * s), 20 * np.sin(s)])
    if grid:
        xy = np.round(xy)
        xy = xy[np.r_[True, np.any(np.diff(xy, axis=0) != 0.0, axis=1)]]
    return PathProjector(global_path_from_centreline(xy, closed=closed).polyline)
