"""Centrelines built from segments: straights, arcs and weaves, closed into loops.

A centreline is a sequence of segments with a curvature each: straights (0),
arcs (+-1/R, left positive) and a slalom (a cosine). The curvature profile
is smoothed (a Gaussian over ~1.5 m, circular for a loop) so that curvature
ramps in and out of corners like a clothoid, then integrated to heading and
position. Smoothing never raises the curvature above the largest of the
segments', so a loop of arcs no tighter than R has no point tighter than R.

A loop closes by resizing its free straights (``close_loop``): each step
linearises the miss in the straights' lengths (a straight of heading h moves
the end by its change of length times (cos h, sin h)) and solves for the
smallest change within each straight's bounds.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray
from scipy.ndimage import gaussian_filter1d

FloatArray = NDArray[np.float64]

STEP = 0.05  # [m] integration step of the centreline
SMOOTH_SIGMA_M = 1.5  # [m] Gaussian smoothing of the curvature profile
CLOSE_ITERATIONS = 20  # Newton steps of the loop closure
STALL_RATIO = 0.9  # a step that does not shrink the miss by a tenth is not converging


class LoopClosureError(ValueError):
    """The free straights cannot close the loop within their bounds."""


@dataclass(frozen=True)
class Segment:
    """A piece of centreline with a curvature profile.

    Attributes:
        length: [m].
        curvature: maps arc length within the segment (k,) [m] to curvature [1/m].
        free: a straight whose length the loop closure may change.
        min_length: the shortest a free straight may become [m].
        max_length: the longest a free straight may become [m].
    """

    length: float
    curvature: Callable[[FloatArray], FloatArray]
    free: bool = False
    min_length: float = 1.0
    max_length: float = math.inf


def straight(
    length: float, free: bool = False, min_length: float = 1.0, max_length: float = math.inf
) -> Segment:
    """A straight of ``length`` [m]; a free one stays within [min_length, max_length] [m]."""
    return Segment(length, np.zeros_like, free, min_length, max_length)


def arc(radius: float, angle_deg: float) -> Segment:
    """An arc of ``radius`` [m] turning ``angle_deg`` (left positive)."""
    angle = math.radians(angle_deg)
    length = radius * abs(angle)
    return Segment(length, lambda s: np.full_like(s, math.copysign(1.0 / radius, angle)))


def slalom(length: float, radius: float, periods: int) -> Segment:
    """A weave: curvature (1/radius) cos(2 pi periods s / length), no net turn."""
    wavelength = length / periods
    return Segment(length, lambda s: np.cos(2 * np.pi * s / wavelength) / radius)


def curvature_profile(
    segments: Sequence[Segment], closed: bool, step: float = STEP
) -> tuple[FloatArray, list[slice]]:
    """Curvature at every ``step`` [m] of the centreline, smoothed, and the free
    straights' samples."""
    parts, free, start = [], [], 0
    for seg in segments:
        count = max(1, round(seg.length / step))
        s = (np.arange(count, dtype=np.float64) + 0.5) * (seg.length / count)
        kappa = seg.curvature(s) * (seg.length / count) / step  # keep the segment's total turn
        parts.append(kappa)
        if seg.free:
            free.append(slice(start, start + count))
        start += count
    kappa = np.concatenate(parts)
    mode = "wrap" if closed else "nearest"
    return gaussian_filter1d(kappa, SMOOTH_SIGMA_M / step, mode=mode), free


def integrate(
    kappa: FloatArray, heading0: float = 0.0, step: float = STEP
) -> tuple[FloatArray, FloatArray]:
    """Points (n + 1, 2) [m] and headings (n,) [rad] of a curvature profile at ``step``."""
    heading = heading0 + np.cumsum(kappa * step) - 0.5 * kappa * step
    steps = step * np.column_stack([np.cos(heading), np.sin(heading)])
    return np.vstack([[0.0, 0.0], np.cumsum(steps, axis=0)]), heading


def close_loop(segments: Sequence[Segment]) -> tuple[FloatArray, FloatArray, FloatArray]:
    """A closed centreline: points (n, 2) [m], headings (n,) [rad], curvature (n,) [1/m],
    every STEP (``resize_to_close``)."""
    _, points, heading, kappa = resize_to_close(segments)
    return points, heading, kappa


def resize_to_close(
    segments: Sequence[Segment], step: float = STEP
) -> tuple[list[Segment], FloatArray, FloatArray, FloatArray]:
    """The segments with their free straights resized to close the loop, and its
    points (n, 2) [m], headings (n,) [rad] and curvature (n,) [1/m] every ``step``.

    The free straights (at least two, not parallel) are resized until the
    loop closes to within a ``step``; the last few millimetres are spread
    along the loop. The segments' total turn must already be a whole turn.
    A coarse ``step`` finds lengths that nearly close the loop quickly; run
    again at STEP from them, it takes a step or two.

    Raises:
        LoopClosureError: fewer than two free straights, or no lengths
            within their bounds close the loop.
    """
    segs = list(segments)
    free_idx = [i for i, seg in enumerate(segs) if seg.free]
    if len(free_idx) < 2:
        raise LoopClosureError("a loop needs at least two free straights to close")
    previous = math.inf
    for _ in range(CLOSE_ITERATIONS):
        kappa, free = curvature_profile(segs, closed=True, step=step)
        points, heading = integrate(kappa, step=step)
        miss = points[-1] - points[0]
        size = float(np.hypot(*miss))
        if size < step:
            spread = np.linspace(0.0, 1.0, len(points))[:, None] * miss
            return segs, (points - spread)[:-1], heading, kappa
        if size > STALL_RATIO * previous:
            break  # Newton's steps shrink the miss many times over; these do not
        previous = size
        dirs = np.column_stack(
            [[np.cos(heading[f]).mean(), np.sin(heading[f]).mean()] for f in free]
        )
        for i, d in zip(free_idx, _length_changes(dirs, miss, segs, free_idx), strict=True):
            segs[i] = replace(segs[i], length=segs[i].length + float(d))
    raise LoopClosureError("loop closure did not converge")


def _length_changes(
    dirs: FloatArray, miss: FloatArray, segs: list[Segment], free_idx: list[int]
) -> FloatArray:
    """Changes of the free straights' lengths [m] that cancel ``miss`` (2,) [m].

    Two straights: the one exact solution. More: the smallest changes
    weighted by the straights' lengths (a long straight gives more),
    delta = W D' (D W D')^-1 (-miss) with D the (2, k) directions and W =
    diag(lengths); a straight that would leave its bounds is held at the
    bound and the rest solved again (an active set, at most k rounds).
    """
    lengths = np.array([segs[i].length for i in free_idx])
    lo = np.array([segs[i].min_length for i in free_idx]) - lengths
    hi = np.array([segs[i].max_length for i in free_idx]) - lengths
    if len(free_idx) == 2:
        try:
            delta: FloatArray = np.asarray(np.linalg.solve(dirs, -miss), dtype=np.float64)
        except np.linalg.LinAlgError:
            raise LoopClosureError("the two free straights are parallel") from None
        _check_bounds(delta, lo, hi, lengths)
        return delta
    delta = np.zeros(len(lengths))
    held = np.zeros(len(lengths), dtype=bool)
    for _ in range(len(lengths)):
        rest = -miss - dirs[:, held] @ delta[held]
        d, w = dirs[:, ~held], np.maximum(lengths[~held], 1.0)
        gram = (d * w) @ d.T
        if abs(np.linalg.det(gram)) < 1e-9:
            break
        delta[~held] = w * (d.T @ np.linalg.solve(gram, rest))
        low, high = delta < lo - 1e-9, delta > hi + 1e-9
        if not (low.any() or high.any()):
            return delta
        delta = np.asarray(np.clip(delta, lo, hi), dtype=np.float64)
        held |= low | high
    raise LoopClosureError("no lengths of the free straights within their bounds close the loop")


def _check_bounds(delta: FloatArray, lo: FloatArray, hi: FloatArray, lengths: FloatArray) -> None:
    if np.any(delta < lo - 1e-9) or np.any(delta > hi + 1e-9):
        k = int(np.argmax(np.maximum(lo - delta, delta - hi)))
        raise LoopClosureError(
            f"loop closure needs a free straight of {lengths[k] + delta[k]:.1f} m"
        )
