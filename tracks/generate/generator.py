"""The random track generator: FS-rule loops from a seed (issue 15).

``generate_track(seed, spec)`` makes a closed cone track: a random layout of
straights, corners, hairpins (some tighter than the FS rule's regular ones,
down to what the car can turn), S-bends, chicanes and slaloms (layout.py),
closed into a loop (centreline.py), checked, and coned (loop.py): blue on
the left, yellow on the right, at most ``max_spacing`` apart and closer in
corners, four big orange cones at the start/finish line standing
``gate_offset`` outside the lane, and the car's standing start 4 m behind
the line.

Checks on each attempt: the loop closes with every straight within its
bounds (3-75 m; FS: <= 80 m), the lap is within the length range, and no
two parts of the track that are not the same bend come closer than the
lane's width plus ``leg_gap`` (which also rules out self-intersection):
points closer than that must lie within a quarter circle of that diameter
of each other along the loop. Every arc is at least ``min_radius``, and
smoothing never tightens a curve, so neither is the loop.

Why our own and not the ``random-track-generator`` package (1.1.0, TU Delft,
read for this): it pins ``numpy<2`` (conesim runs numpy 2) and needs shapely
and gpxpy; its Voronoi regions give no control over hairpins, chicanes or
the tightest radius; it places no start gate; and it retries in
``while True`` loops (``except: continue`` around a seeded attempt repeats
the same failure forever), which is the hang the issue reports. Ours is
numpy and scipy only, bounded by ``max_attempts``, and deterministic: each
attempt draws from ``numpy.random.default_rng([seed, attempt])``, so the
same seed and spec give the same cones, bit for bit, in any process.
"""

from __future__ import annotations

import math
from collections import Counter

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from conesim.tracks.generate.centreline import STEP, LoopClosureError, resize_to_close
from conesim.tracks.generate.layout import random_layout
from conesim.tracks.generate.loop import loop_centreline, loop_cones, start_pose
from conesim.tracks.generate.spec import GeneratedTrack, TrackGenerationError, TrackSpec
from conesim.tracks.kinds import Layout
from conesim.tracks.model import Track

FloatArray = NDArray[np.float64]

CHECK_SPACING = 0.5  # [m] the clearance check's sampling of the centreline
COARSE_STEP = 0.5  # [m] the first, coarse closure of a layout
SPACING_WINDOW_M = 6.0  # [m] cone spacing follows the tightest curvature this near


def generate_track(seed: int, spec: TrackSpec | None = None) -> Track:
    """A random FS-rule closed track for ``seed`` (module docstring).

    Args:
        seed: an integer in [0, 2**63).
        spec: the generator's settings (default ``TrackSpec()``: medium).

    Raises:
        TrackGenerationError: no attempt of ``spec.max_attempts`` made a
            track; the message names the seed, the spec and the reasons.
        ValueError: a seed out of range.
    """
    recipe = GeneratedTrack(seed, spec or TrackSpec())
    spec = recipe.spec
    reasons: Counter[str] = Counter()
    for attempt in range(spec.max_attempts):
        rng = np.random.default_rng([seed, attempt])
        layout = random_layout(rng, spec)
        if layout is None:
            reasons["the features do not fit the lap length or turn"] += 1
            continue
        lo, hi = spec.lengths
        clearance = layout.width + spec.leg_gap
        try:  # coarsely first: most layouts fail here, at a tenth of the cost
            segments, coarse, _, _ = resize_to_close(layout.segments, COARSE_STEP)
            fits = lo <= len(coarse) * COARSE_STEP <= hi
            apart = fits and legs_apart(coarse, COARSE_STEP, clearance)
            loop = loop_centreline(segments, layout.line_at) if apart else None
        except LoopClosureError:
            reasons["the loop does not close"] += 1
            continue
        if not fits or (loop is not None and not lo <= loop.length <= hi):
            reasons[f"the lap is not {lo:g}-{hi:g} m long"] += 1
            continue
        if loop is None or not legs_apart(loop.points, STEP, clearance):
            reasons["parts of the loop come too close"] += 1
            continue
        cones, kinds = loop_cones(
            loop, layout.width, gate_offset=layout.gate_offset, min_spacing=spec.min_spacing,
            max_spacing=spec.max_spacing, spacing_window=SPACING_WINDOW_M,
        )  # fmt: skip
        description = (
            f"generated (seed {seed}, {spec.size}): {loop.length:.0f} m, "
            f"{layout.width:.2f} m wide, gate {layout.gate_offset:.2f} m outside the lane; "
            + ", ".join(layout.features)
        )
        return Track(
            recipe.name, cones, kinds, start_pose(loop), Layout.CLOSED, description=description
        )
    why = "; ".join(f"{reason} ({n}x)" for reason, n in reasons.most_common())
    raise TrackGenerationError(
        f"seed {seed}: no track in {spec.max_attempts} attempts ({spec.size}, "
        f"{spec.lengths[0]:g}-{spec.lengths[1]:g} m): {why}"
    )


def legs_apart(centreline: FloatArray, step: float, distance: float) -> bool:
    """Whether points of a closed centreline (n, 2) [m], ``step`` [m] apart, that
    are closer than ``distance`` [m] are one bend.

    Two points closer than ``distance`` must lie within a quarter of the
    circle of that diameter of each other along the loop (pi/2 * distance):
    so are points of one bend, and not of two legs side by side.
    """
    every = max(1, round(CHECK_SPACING / step))
    points = centreline[::every]
    pairs = cKDTree(points).query_pairs(distance, output_type="ndarray")
    if len(pairs) == 0:
        return True
    n = len(points)
    apart = np.abs(pairs[:, 0] - pairs[:, 1])
    along = np.minimum(apart, n - apart) * (every * step)
    return bool(np.all(along <= 0.5 * math.pi * distance))
