"""Hard loops for the autopilot: hairpins, S-bends, chicanes and a start gate wider than the lane.

A stand-in for the random FS generator where the driving tests and
``benchmarks/bench_driving.py`` need tracks the planner was not tuned on:
``hard_loop(seed)`` composes a loop, deterministic per seed, of two long
free straights (which close it) and two ends, each a hairpin of 3-4.5 m
lane-centre radius (the FS minimum is 9 m outside diameter: 3 m in a 3 m
lane) or a pair of 90 deg corners, with S-bends, chicanes or kinks between.
The lane is 3-3.8 m wide and the big orange cones of the gate stand up to
0.6 m outside its edges, as on real tracks. ``hairpin_loop`` is the one
fixed layout the tests use.
"""

from __future__ import annotations

import numpy as np

from conesim.tracks.generate.centreline import LoopClosureError, Segment, arc, straight
from conesim.tracks.generate.loop import loop_centreline, loop_cones, start_pose
from conesim.tracks.kinds import Layout
from conesim.tracks.model import Track
from conesim.tracks.validate import check_report

ATTEMPTS = 50  # draws tried per seed
LINE_AT = 12.0  # [m] the start/finish line this far into the first straight


def _feature(rng: np.random.Generator) -> list[Segment]:
    """A piece with no net turn: an S-bend, a chicane, a kink, or nothing."""
    kind = rng.integers(4)
    radius = float(rng.uniform(4.0, 9.0))
    angle = float(rng.uniform(30.0, 70.0)) * (1.0 if rng.random() < 0.5 else -1.0)
    if kind == 0:  # S-bend
        return [arc(radius, angle), arc(radius, -angle), straight(4.0)]
    if kind == 1:  # chicane
        return [arc(radius, angle / 2), straight(2.0), arc(radius, -angle), straight(2.0),
                arc(radius, angle / 2), straight(4.0)]  # fmt: skip
    if kind == 2:  # kink
        return [arc(radius * 1.5, angle / 2), arc(radius * 1.5, -angle / 2), straight(4.0)]
    return [straight(6.0)]


def _end(rng: np.random.Generator, hairpin_radius: float) -> list[Segment]:
    """A half turn: a hairpin of ``hairpin_radius`` [m] or two corners with a straight."""
    if rng.random() < 0.6:
        return [arc(hairpin_radius, 180.0)]
    radius = float(rng.uniform(4.0, 10.0))
    return [arc(radius, 90.0), straight(float(rng.uniform(6.0, 18.0))), arc(radius, 90.0)]


def hard_segments(rng: np.random.Generator) -> tuple[list[Segment], float, float]:
    """The segments, the lane width [m] and the gate's offset [m] of one draw."""
    width = float(rng.uniform(3.0, 3.8))
    gate_offset = float(rng.choice([0.0, 0.3, 0.6]))
    radii = rng.uniform(3.0, 4.5, size=2)
    segments = [straight(float(rng.uniform(30.0, 50.0)), free=True, min_length=20.0)]
    segments += _feature(rng) + _end(rng, float(radii[0])) + [straight(6.0)]
    # the back straight, at an angle: two straights at different headings close the loop
    bend = float(rng.uniform(10.0, 45.0)) * (1.0 if rng.random() < 0.5 else -1.0)
    segments += [arc(12.0, bend), straight(float(rng.uniform(20.0, 40.0)), free=True,
                 min_length=8.0), arc(12.0, -bend)]  # fmt: skip
    segments += _feature(rng) + _end(rng, float(radii[1])) + [straight(6.0)]
    return segments, width, gate_offset


def loop_from_segments(
    name: str, segments: list[Segment], width: float, gate_offset: float, description: str
) -> Track:
    """A closed track of ``segments``, ``width`` [m] wide, its gate ``gate_offset`` [m]
    outside the lane's edges, the line ``LINE_AT`` into the first segment."""
    loop = loop_centreline(segments, LINE_AT)
    cones, kinds = loop_cones(loop, width, gate_offset=gate_offset)
    return Track(name, cones, kinds, start_pose(loop), Layout.CLOSED, description=description)


def hard_loop(seed: int) -> Track:
    """A hard loop, the same for the same seed (module docstring).

    The seed's draws are tried in turn until one closes with no validator error.

    Raises:
        LoopClosureError: none of ``ATTEMPTS`` draws closes.
    """
    for attempt in range(ATTEMPTS):
        segments, width, gate = hard_segments(np.random.default_rng([15, seed, attempt]))
        try:
            track = loop_from_segments(
                f"hard_{seed}", segments, width, gate,
                f"hard loop {seed}: {width:.2f} m wide, gate {gate:.1f} m outside the lane",
            )  # fmt: skip
        except LoopClosureError:
            continue
        if not check_report(track)["errors"]:  # e.g. a loop that crosses itself
            return track
    raise LoopClosureError(f"hard_loop({seed}): no loop closed in {ATTEMPTS} draws")


def hairpin_loop(radius: float = 3.0, width: float = 3.0, gate_offset: float = 0.5) -> Track:
    """An oval of two hairpins of ``radius`` [m] at the lane's centre, ``width`` [m]
    wide, with an S-bend on the back straight and a gate ``gate_offset`` [m] wide
    of the lane (the FS hairpin minimum: 9 m outside diameter in a 3 m lane)."""
    segments = [
        straight(30.0, free=True, min_length=20.0),
        arc(radius, 180.0),
        straight(8.0),
        arc(6.0, -45.0),
        arc(6.0, 45.0),
        arc(12.0, 20.0),
        straight(6.0, free=True, min_length=1.0),
        arc(12.0, -20.0),
        arc(radius, 180.0),
        straight(6.0),
    ]
    return loop_from_segments(
        f"hairpin_{radius:g}", segments, width, gate_offset,
        f"two hairpins of {radius:g} m lane-centre radius, {width:g} m wide",
    )  # fmt: skip
