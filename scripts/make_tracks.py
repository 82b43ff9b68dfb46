"""Generate the shipped tracks in ``tracks/data``.

Each track is built from a parametric centreline, cones are placed along its
edges as FS organisers do, and the result is written in our own format
(``<name>.yaml``) with its global path (``<name>_path.csv``, the ROS pipeline's
``lat,lon,cov`` CSV). Run from the repository root::

    python scripts/make_tracks.py [--out tracks/data] [--plot DIR]

The output is deterministic: running it twice writes identical files.

Loops (trackdrive, autocross) are a sequence of segments with a curvature
each: straights (0), arcs (+-1/R, left positive) and a slalom (a cosine).
The curvature profile is smoothed (a Gaussian over ~1.5 m, circular for a
loop) so that curvature ramps in and out of corners like a clothoid, then
integrated to heading and position. Two "free" straights are lengthened or
shortened (Newton steps on their two non-parallel directions) until the loop
closes exactly.

Cones (REFERENCES.md, "Formula Student tracks"): blue at +w/2 (left), yellow
at -w/2 (right), spaced at most 4.5 m on straights (FS: <= 5 m) and closer in
corners (``cone_spacing``); 4 big orange cones at the start/finish line (two
each side, 0.6 m apart, as in fssim). The acceleration and skidpad layouts
copy fssim's published ones (acceleration: 3.8 m wide, 75 m timed, orange
braking zone to 175 m; skidpad: the FS circles).

Global path covariance: RTK fixed (~2 cm sigma, 0.0004 m^2) with small
variation, and an "RTK float under trees" stretch rising to ~0.02 m^2, above
the ROS pipeline's red threshold 0.0025 m^2.
"""

from __future__ import annotations

import argparse
import math
import zlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from numpy.typing import NDArray
from scipy.ndimage import gaussian_filter1d

from conesim.core.pose import Pose2D
from conesim.tracks import ConeKind, Layout, Track, check_report, read_track, write_track
from conesim.tracks.global_path import global_path_from_centreline, write_global_path_csv

FloatArray = NDArray[np.float64]

ROOT = Path(__file__).resolve().parents[1]
STEP = 0.05  # [m] integration step of the centreline
SMOOTH_SIGMA_M = 1.5  # [m] Gaussian smoothing of the curvature profile
MAX_SPACING = 4.5  # [m] cone spacing on straights (FS: <= 5 m)
MIN_SPACING = 1.5  # [m] cone spacing in the tightest corners
BIG_ORANGE_HALF_GAP = 0.3  # [m] big orange cones stand +-0.3 m from the line (fssim)
START_BEHIND_LINE = 4.0  # [m] standing start behind the start/finish line
RTK_FIXED_COV = 0.0004  # [m^2] 2 cm sigma
RTK_FLOAT_COV = 0.02  # [m^2] ~14 cm sigma: the ROS pipeline draws it red (> 0.0025 m^2)


@dataclass(frozen=True)
class Segment:
    """A piece of centreline with a curvature profile.

    Attributes:
        length: [m].
        curvature: maps arc length within the segment (k,) [m] to curvature [1/m].
        free: a straight whose length the loop closure may change.
    """

    length: float
    curvature: Callable[[FloatArray], FloatArray]
    free: bool = False


def straight(length: float, free: bool = False) -> Segment:
    """A straight of ``length`` [m]."""
    return Segment(length, np.zeros_like, free)


def arc(radius: float, angle_deg: float) -> Segment:
    """An arc of ``radius`` [m] turning ``angle_deg`` (left positive)."""
    angle = math.radians(angle_deg)
    length = radius * abs(angle)
    return Segment(length, lambda s: np.full_like(s, math.copysign(1.0 / radius, angle)))


def slalom(length: float, radius: float, periods: int) -> Segment:
    """A weave: curvature (1/radius) cos(2 pi periods s / length), no net turn."""
    wavelength = length / periods
    return Segment(length, lambda s: np.cos(2 * np.pi * s / wavelength) / radius)


def curvature_profile(segments: Sequence[Segment], closed: bool) -> tuple[FloatArray, list[slice]]:
    """Curvature at every STEP of the centreline, smoothed, and the free straights' samples."""
    parts, free, start = [], [], 0
    for seg in segments:
        count = max(1, round(seg.length / STEP))
        s = (np.arange(count, dtype=np.float64) + 0.5) * (seg.length / count)
        kappa = seg.curvature(s) * (seg.length / count) / STEP  # keep the segment's total turn
        parts.append(kappa)
        if seg.free:
            free.append(slice(start, start + count))
        start += count
    kappa = np.concatenate(parts)
    mode = "wrap" if closed else "nearest"
    return gaussian_filter1d(kappa, SMOOTH_SIGMA_M / STEP, mode=mode), free


def integrate(kappa: FloatArray, heading0: float = 0.0) -> tuple[FloatArray, FloatArray]:
    """Points (n + 1, 2) [m] and headings (n,) [rad] of a curvature profile at STEP."""
    heading = heading0 + np.cumsum(kappa * STEP) - 0.5 * kappa * STEP
    steps = STEP * np.column_stack([np.cos(heading), np.sin(heading)])
    return np.vstack([[0.0, 0.0], np.cumsum(steps, axis=0)]), heading


def closed_loop(segments: list[Segment]) -> tuple[FloatArray, FloatArray, FloatArray]:
    """A closed centreline: points (n, 2) [m], headings (n,) [rad], curvature (n,) [1/m].

    The two free straights are resized (Newton steps) until the loop closes
    to within a STEP; the last few millimetres are spread along the loop.
    """
    segs = list(segments)
    free_idx = [i for i, seg in enumerate(segs) if seg.free]
    if len(free_idx) != 2:
        raise ValueError("a loop needs exactly two free straights to close")
    for _ in range(20):
        kappa, free = curvature_profile(segs, closed=True)
        points, heading = integrate(kappa)
        miss = points[-1] - points[0]
        if np.hypot(*miss) < STEP:
            spread = np.linspace(0.0, 1.0, len(points))[:, None] * miss
            return (points - spread)[:-1], heading, kappa
        dirs = np.column_stack(
            [[np.cos(heading[f]).mean(), np.sin(heading[f]).mean()] for f in free]
        )
        delta = np.linalg.solve(dirs, -miss)
        for i, d in zip(free_idx, delta, strict=True):
            new = segs[i].length + float(d)
            if new <= 1.0:
                raise ValueError(f"loop closure needs a free straight of {new:.1f} m")
            segs[i] = straight(new, free=True)
    raise ValueError("loop closure did not converge")


def cone_spacing(radius: FloatArray) -> FloatArray:
    """Cone spacing [m] on a boundary of local radius ``radius`` [m]: 0.9 sqrt(R),
    from 1.5 m in the tightest corners to 4.5 m on straights (FS: <= 5 m)."""
    return np.clip(0.9 * np.sqrt(radius), MIN_SPACING, MAX_SPACING)


def place_cones(edge: FloatArray, edge_kappa: FloatArray) -> FloatArray:
    """Cones along a closed edge (n, 2) [m], starting at its first point.

    The cone density 1/spacing is integrated along the edge and the cones
    stand at equal steps of it, so that spacing follows the curvature and the
    last gap equals its neighbours.
    """
    seg = np.hypot(*np.diff(np.vstack([edge, edge[:1]]), axis=0).T)
    density = 1.0 / cone_spacing(1.0 / np.maximum(np.abs(edge_kappa), 1e-6))
    cum = np.concatenate([[0.0], np.cumsum(density * seg)])
    count = math.ceil(cum[-1])
    s_edge = np.concatenate([[0.0], np.cumsum(seg)])
    s = np.interp(np.arange(count) * cum[-1] / count, cum, s_edge)
    ring = np.vstack([edge, edge[:1]])
    return np.column_stack([np.interp(s, s_edge, ring[:, 0]), np.interp(s, s_edge, ring[:, 1])])


def loop_track(
    name: str, segments: list[Segment], width: float, line_at: float, description: str
) -> Track:
    """A closed track from segments, the start/finish line ``line_at`` [m] from the start."""
    points, heading, kappa = closed_loop(segments)
    shift = round(line_at / STEP)
    points, heading, kappa = (np.roll(a, -shift, axis=0) for a in (points, heading, kappa))
    # Smoothing leaks a little of the last corner's turn past the start; turn
    # the whole loop so that it starts exactly eastwards at the origin.
    c, s = math.cos(heading[0]), math.sin(heading[0])
    points = (points - points[0]) @ np.array([[c, -s], [s, c]])
    heading = heading - heading[0]
    normal = np.column_stack([-np.sin(heading), np.cos(heading)])
    cones, kinds = [], []
    for sign, kind in ((1.0, ConeKind.BLUE), (-1.0, ConeKind.YELLOW)):
        offset = sign * width / 2
        edge = points + offset * normal
        placed = place_cones(edge, kappa / (1.0 - kappa * offset))
        cones.append(placed[1:])  # the cone on the line gives way to the big orange ones
        kinds += [kind] * (len(placed) - 1)
        along = np.array([np.cos(heading[0]), np.sin(heading[0])])
        for d in (-BIG_ORANGE_HALF_GAP, BIG_ORANGE_HALF_GAP):
            cones.append((edge[0] + d * along)[None])
            kinds.append(ConeKind.BIG_ORANGE)
    back = -round(START_BEHIND_LINE / STEP)
    start = Pose2D(float(points[back, 0]), float(points[back, 1]), float(heading[back]))
    return Track(
        name, np.vstack(cones), tuple(kinds), start, Layout.CLOSED, description=description
    )


def trackdrive() -> Track:
    """THE DEFAULT: a gentle FS trackdrive-style loop, ~270 m, 3.8 m wide."""
    segments = [
        straight(45.0),
        arc(15.0, 90),
        straight(15.0),
        arc(22.0, 40),
        arc(22.0, -40),
        straight(10.0),
        arc(12.0, 90),
        straight(30.0, free=True),
        arc(12.0, 60),
        arc(16.0, -60),
        arc(12.0, 90),
        straight(40.0, free=True),
        arc(14.0, 90),
    ]
    return loop_track(
        "trackdrive",
        segments,
        width=3.8,
        line_at=15.0,
        description="FS trackdrive-style loop: gentle and medium corners (radius >= 12 m), "
        "3.8 m wide. Generated by scripts/make_tracks.py.",
    )


def autocross() -> Track:
    """A closed autocross: hairpin, chicane, slalom and a long straight (<= 80 m)."""
    segments = [
        straight(68.0),
        arc(6.5, 180),  # hairpin: 16.5 m outside diameter (FS: >= 9 m)
        straight(6.0),
        arc(9.0, -35),  # chicane
        arc(9.0, 70),
        arc(9.0, -35),
        straight(4.0),
        arc(10.0, -90),
        slalom(48.0, 11.0, 2),
        straight(6.0),
        arc(10.0, 90),
        straight(25.0, free=True),
        arc(12.0, 90),
        straight(50.0, free=True),
        arc(11.0, 90),
        straight(6.0),
    ]
    return loop_track(
        "autocross",
        segments,
        width=3.5,
        line_at=8.0,
        description="FS autocross-style loop: a 74 m straight into a hairpin (16.5 m outside "
        "diameter), a chicane, a slalom; 3.5 m wide. Generated by scripts/make_tracks.py.",
    )


def acceleration() -> Track:
    """FS acceleration as fssim lays it out: 3.8 m wide, 75 m timed, braking to 175 m."""
    half = 1.9
    cones, kinds = [], []
    for x in [-5.0, *np.arange(5.0, 71.0, 5.0)]:  # a staging pair behind the start line
        cones += [[x, half], [x, -half]]
        kinds += [ConeKind.BLUE, ConeKind.YELLOW]
    for x in (-0.3, 0.3, 74.7, 75.3):  # start at 0 m, finish at 75 m
        cones += [[x, half], [x, -half]]
        kinds += [ConeKind.BIG_ORANGE] * 2
    for x in np.arange(80.0, 176.0, 5.0):  # braking zone
        cones += [[x, half], [x, -half]]
        kinds += [ConeKind.ORANGE] * 2
    return Track(
        "acceleration",
        np.array(cones, dtype=float),
        tuple(kinds),
        Pose2D(-2.0, 0.0, 0.0),
        Layout.OPEN,
        description="FS acceleration (fssim layout): 3.8 m wide lane, start line at 0 m, "
        "finish at 75 m, orange braking zone to 175 m. Generated by scripts/make_tracks.py.",
    )


def skidpad() -> Track:
    """The FS skidpad: circles of 15.25 / 21.25 m diameter, centres 18.25 m apart.

    Entry heading east along y = 0; right circle (driven clockwise) centred at
    (0, -9.125), left (counter-clockwise) at (0, 9.125). As in fssim, cone
    centres stand 0.15 m inside the inner and outside the outer lines, 16
    angular slots per ring, and outer-ring cones that would stand in the other
    circle's track are left out. Colours follow blue-left/yellow-right for the
    car driving each circle: right circle inner yellow, outer blue; left
    circle inner blue, outer yellow.
    """
    half_gap, r_in, r_out = 18.25 / 2, 15.25 / 2 - 0.15, 21.25 / 2 + 0.15
    cones, kinds = [], []
    for cy, inner, outer in (
        (-half_gap, ConeKind.YELLOW, ConeKind.BLUE),
        (half_gap, ConeKind.BLUE, ConeKind.YELLOW),
    ):
        angles = np.arange(16) * (2 * np.pi / 16) + np.pi / 2
        centre = np.array([0.0, cy])
        for r, kind in ((r_in, inner), (r_out, outer)):
            for a in angles:
                p = centre + r * np.array([np.cos(a), np.sin(a)])
                if kind == outer and np.hypot(p[0], p[1] + cy) < r_out + 0.5:
                    continue  # inside the other circle's track
                cones.append(p)
                kinds.append(kind)
    for x in (-15.0, -11.25, 11.0, 16.0, 21.0):
        cones += [np.array([x, 1.65]), np.array([x, -1.65])]
        kinds += [ConeKind.ORANGE] * 2
    for x in (-1.3, 1.3):
        cones += [np.array([x, 2.0]), np.array([x, -2.0])]
        kinds += [ConeKind.BIG_ORANGE] * 2
    return Track(
        "skidpad",
        np.array(cones),
        tuple(kinds),
        Pose2D(-16.5, 0.0, 0.0),
        Layout.SKIDPAD,
        description="FS skidpad: enter, 2 laps clockwise on the right circle, 2 laps "
        "counter-clockwise on the left, exit. Generated by scripts/make_tracks.py.",
    )


def path_covariance(name: str, count: int) -> FloatArray:
    """Per-point covariance [m^2]: RTK fixed with small variation, plus one RTK
    float stretch ("under trees") over a fifth of the path, above 0.0025 m^2."""
    rng = np.random.default_rng(zlib.crc32(name.encode()))
    base = RTK_FIXED_COV * np.exp(0.3 * gaussian_filter1d(rng.standard_normal(count), 5.0) * 3)
    u = np.arange(count) / count
    centre, half = 0.55, 0.1
    bump = np.clip(1.0 - np.abs(u - centre) / half, 0.0, 1.0)
    bump = 0.5 - 0.5 * np.cos(np.pi * bump)  # raised-cosine ramps in and out
    return base + (RTK_FLOAT_COV - RTK_FIXED_COV) * bump


def write(track: Track, out: Path) -> Track:
    """Write the track and its global path; return the track as read back."""
    out.mkdir(parents=True, exist_ok=True)
    path_file = out / f"{track.name}_path.csv"
    centreline = track.centreline
    cov = path_covariance(track.name, len(centreline))
    closed = track.layout == Layout.CLOSED
    write_global_path_csv(path_file, global_path_from_centreline(centreline, closed, cov=cov))
    path_file.chmod(0o644)  # written through mkstemp (0600); package data is for everyone
    linked = Track(
        track.name,
        track.cones,
        track.kinds,
        track.start_pose,
        track.layout,
        global_path_file=path_file,
        description=track.description,
    )
    written = write_track(linked, out / f"{track.name}.yaml")
    back = read_track(written)
    if back != linked:
        raise AssertionError(f"{track.name}: the written track does not read back identically")
    return back


def plot(track: Track, out: Path) -> None:
    """A quick PNG of cones and centreline, for looking at a design."""
    colours = {"blue": "b", "yellow": "gold", "orange": "orange", "big_orange": "r", "unknown": "k"}
    fig, ax = plt.subplots(figsize=(10, 8))
    for kind in ConeKind:
        c = track.cones_of(kind)
        ax.scatter(c[:, 0], c[:, 1], s=8, c=colours[str(kind)])
    ax.plot(*track.centreline.T, "k-", lw=0.5)
    ax.plot(*track.start_finish.T, "r-")
    ax.plot(track.start_pose.x, track.start_pose.y, "g>")
    ax.set_aspect("equal")
    fig.savefig(out / f"{track.name}.png", dpi=110)
    plt.close(fig)


def main(argv: Sequence[str] | None = None) -> int:
    """Build, check and write every shipped track."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "tracks" / "data")
    parser.add_argument("--plot", type=Path, help="also draw each track into this directory")
    args = parser.parse_args(argv)
    failed = False
    for build in (trackdrive, autocross, acceleration, skidpad):
        track = write(build(), args.out)
        report = check_report(track)
        counts = " ".join(f"{k}={n}" for k, n in report["cones"].items())
        print(
            f"{track.name:13s} {report['length_m']:7.1f} m  width "
            f"{report['width_min_m']:.2f}-{report['width_max_m']:.2f} m  {counts}"
        )
        for line in report["warnings"]:
            print(f"  warning: {line}")
        for line in report["errors"]:
            print(f"  ERROR: {line}")
            failed = True
        if args.plot:
            args.plot.mkdir(parents=True, exist_ok=True)
            plot(track, args.plot)
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
