"""A random loop layout: the features of an FS track in a random order.

One attempt (``random_layout``) draws, from its own random generator:

1. the lap length (within the spec's range, 10 % in from its ends) and
   the lane's width;
2. the hairpins: each turns 165-195 deg at a lane-centre radius within
   ``hairpin_radius``, or, for a ``tight_share`` of them, down to
   ``min_radius``; mostly the loop's way round, sometimes against it;
3. other features until their arcs are about 45 % of the lap: S-bends
   (two opposite arcs), chicanes (+a, -2a, +a), slaloms and corners, each
   mostly turning the way that keeps the loop's turn so far below 270 deg;
4. the corners that make up the rest of the loop's whole turn (+-360 deg),
   each 25-160 deg, by a Dirichlet split of what is left;
5. the order of the features, shuffled, with a free straight between each
   two (at least 3 m) and a start straight first and last (at least 20 m, the
   gate and the standing start on it); the straights share what is left of
   the lap. Then mirrored with probability 1/2 (a clockwise loop).

Every arc is at least ``min_radius``, so the smoothed loop is nowhere
tighter. Whether the loop closes, keeps its legs apart and has the right
length is checked by the generator, which then tries the next attempt.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from conesim.tracks.generate.centreline import Segment, arc, slalom, straight
from conesim.tracks.generate.spec import (
    FS_MAX_CONSTANT_TURN_RADIUS_M,
    FS_MAX_STRAIGHT_M,
    TrackSpec,
)

LENGTH_MARGIN = 0.1  # the lap is drawn from the length range less this share at either end
START_STRAIGHT_M = (20.0, 40.0)  # [m] the start straight: gate, standing start, run-up
MIN_STRAIGHT_M = 3.0  # [m] between two features
FEATURE_SHARE = 0.45  # features (arcs) take about this share of the lap, straights the rest
CORNER_ANGLE_DEG = (25.0, 160.0)  # a corner's turn
HAIRPIN_ANGLE_DEG = (165.0, 195.0)
HAIRPIN_AGAINST = 0.2  # share of hairpins turning against the loop's way round
CORNER_RADIUS_M = (6.0, FS_MAX_CONSTANT_TURN_RADIUS_M - 5.0)
FEATURE_WEIGHTS = {"s_bend": 0.35, "chicane": 0.25, "slalom": 0.1, "corner": 0.3}


@dataclass(frozen=True)
class LoopLayout:
    """One attempt's loop before it is closed.

    Attributes:
        segments: the loop from the start straight on; the straights are free.
        width: the lane's width [m].
        gate_offset: how far the gate stands outside the lane's edges [m].
        line_at: where the start/finish line is along the start straight [m].
        features: what the loop has, in order (``hairpin``, ``tight hairpin``,
            ``s_bend``, ...), for descriptions.
    """

    segments: list[Segment]
    width: float
    gate_offset: float
    line_at: float
    features: list[str]


def random_layout(rng: np.random.Generator, spec: TrackSpec) -> LoopLayout | None:
    """One random layout (module docstring), or None when the draws cannot make one."""
    lo, hi = spec.lengths
    margin = LENGTH_MARGIN * (hi - lo)  # closing the loop changes the length a little
    target = float(rng.uniform(lo + margin, hi - margin))
    width = float(rng.uniform(*spec.width))
    gate_offset = float(rng.uniform(*spec.gate_offset))
    features: list[tuple[str, list[Segment], float]] = []  # kind, arcs, net turn [deg]
    h0, h1 = spec.hairpin_counts
    for _ in range(int(rng.integers(h0, h1 + 1))):
        features.append(_hairpin(rng, spec))
    drawn = sum(_arc_length(f[1]) for f in features)
    kinds = list(FEATURE_WEIGHTS)
    weights = np.array(list(FEATURE_WEIGHTS.values()))
    while drawn < FEATURE_SHARE * target:
        kind = kinds[int(rng.choice(len(kinds), p=weights / weights.sum()))]
        net = sum(f[2] for f in features)
        feature = _feature(rng, kind, spec, toward=1.0 if net < 270.0 else -1.0)
        features.append(feature)
        drawn += _arc_length(feature[1])
    corners = _closing_corners(rng, 360.0 - sum(f[2] for f in features), spec)
    if corners is None:
        return None
    features += corners
    order = rng.permutation(len(features))
    arcs_length = sum(_arc_length(f[1]) for f in features)
    straights_total = target - arcs_length
    start_length = float(rng.uniform(*START_STRAIGHT_M))
    between = straights_total - start_length
    gaps = len(features) - 1
    if gaps < 1 or between < MIN_STRAIGHT_M * gaps:
        return None
    shares = rng.dirichlet(np.ones(gaps))
    lengths = MIN_STRAIGHT_M + (between - MIN_STRAIGHT_M * gaps) * shares
    sense = 1.0 if rng.random() < 0.5 else -1.0
    segments = [straight(start_length, True, START_STRAIGHT_M[0], FS_MAX_STRAIGHT_M - 5.0)]
    names = []
    for k, i in enumerate(order):
        kind, arcs, _ = features[i]
        segments += [_mirrored(a, sense) for a in arcs]
        names.append(kind)
        if k == len(order) - 1:
            break  # the start straight follows the last feature
        length = min(float(lengths[k]), FS_MAX_STRAIGHT_M - 10.0)
        segments.append(straight(length, True, MIN_STRAIGHT_M, FS_MAX_STRAIGHT_M - 5.0))
    line_at = 0.5 * start_length
    return LoopLayout(segments, width, gate_offset, line_at, names)


def _hairpin(rng: np.random.Generator, spec: TrackSpec) -> tuple[str, list[Segment], float]:
    r0, r1 = spec.hairpin_radius
    tight = spec.min_radius < r0 and rng.random() < spec.tight_share
    radius = float(rng.uniform(spec.min_radius, r0) if tight else rng.uniform(r0, r1))
    angle = float(rng.uniform(*HAIRPIN_ANGLE_DEG))
    if rng.random() < HAIRPIN_AGAINST:
        angle = -angle
    return ("tight hairpin" if tight else "hairpin"), [arc(radius, angle)], angle


def _feature(
    rng: np.random.Generator, kind: str, spec: TrackSpec, toward: float
) -> tuple[str, list[Segment], float]:
    """One S-bend, chicane, slalom or corner: its arcs and net turn [deg], turning
    ``toward`` (+1 or -1) three times in four."""
    sign = toward if rng.random() < 0.75 else -toward
    floor = max(spec.min_radius, spec.hairpin_radius[0])
    if kind == "s_bend":
        a1, a2 = rng.uniform(45.0, 100.0, 2)
        low = max(floor, 6.0)
        r1, r2 = rng.uniform(low, max(low, 14.0), 2)
        return kind, [arc(float(r1), sign * a1), arc(float(r2), -sign * a2)], sign * (a1 - a2)
    if kind == "chicane":
        a = float(rng.uniform(25.0, 45.0))
        low = max(floor, 5.0)
        r = float(rng.uniform(low, max(low, 9.0)))
        return kind, [arc(r, sign * a), arc(r, -2 * sign * a), arc(r, sign * a)], 0.0
    if kind == "slalom":
        length = float(rng.uniform(30.0, 45.0))
        low = max(floor, 9.0)
        return kind, [slalom(length, float(rng.uniform(low, max(low, 13.0))), 2)], 0.0
    angle = float(rng.uniform(*CORNER_ANGLE_DEG))
    return "corner", [arc(_corner_radius(rng), sign * angle)], sign * angle


def _closing_corners(
    rng: np.random.Generator, rest: float, spec: TrackSpec
) -> list[tuple[str, list[Segment], float]] | None:
    """Corners that turn ``rest`` [deg] between them, each within CORNER_ANGLE_DEG
    (first, while ``rest`` is below it, corners turning the other way)."""
    lo, hi = CORNER_ANGLE_DEG
    against = []
    while rest < lo:  # turned too far already: a corner the other way first
        angle = float(rng.uniform(30.0, 90.0))
        against.append(("corner", [arc(_corner_radius(rng), -angle)], -angle))
        rest += angle
    count = max(1, math.ceil(rest / (0.6 * hi)))
    angles = rest * rng.dirichlet(np.full(count, 4.0))
    if np.any(angles < lo) or np.any(angles > hi):
        return None
    return against + [("corner", [arc(_corner_radius(rng), float(a))], float(a)) for a in angles]


def _corner_radius(rng: np.random.Generator) -> float:
    lo, hi = CORNER_RADIUS_M
    return float(lo + (hi - lo) * rng.random() ** 2)  # more tight corners than sweepers


def _arc_length(arcs: list[Segment]) -> float:
    return sum(a.length for a in arcs)


def _mirrored(segment: Segment, sense: float) -> Segment:
    if sense > 0:
        return segment
    curvature = segment.curvature
    return Segment(segment.length, lambda s: -curvature(s), segment.free)
