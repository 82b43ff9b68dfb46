"""Planner benchmark: latency per detection and midline accuracy. Prints figures.

1. Latency of ``classify_cones_by_side`` + ``reference_path_planning`` (with
   the speed profile) per detection, with 20, 40 and 80 cones in view, on a
   synthetic winding track (3.5 m wide; the cone spacing is set so that the
   sensor sees that many cones within 30 m ahead). Targets on this machine:
   median <= 0.5 ms, p99 <= 2 ms. Each size is warmed up (20 detections)
   before it is timed: the planner's compiled kernels (``planner.kernels``,
   numba) are compiled on their first call, or loaded from numba's cache, and
   neither belongs in a per-detection latency (the autopilot does it when it
   is built: ``planner.autopilot.warm_up_planner``).
1b. The floor scipy sets: section 1's scenes again, with the planner's two
   scipy calls timed where they happen (``timing.timed_calls`` on
   ``planner.bridges.Delaunay`` and ``planner.spline.splprep``): qhull's
   triangulation of every cone in view with its virtual partners (the ROS pipeline's
   and the issue's "Delaunay on all of them") and the spline fit through the
   midpoints. Per size: the points triangulated, each call's mean time, the
   median per detection of the two together ("scipy") and of everything else
   ("rest": the frame tree, the projection, the compiled steps, the
   messages), and what scipy alone leaves of the 0.5 ms median.
2. Midline accuracy on each shipped track: the car is put on the global path
   every metre for one lap (exact pose in the frame tree), the cones are seen
   by ``sim.sensors.ConeDetector`` with the ``ideal`` and the default noisy
   (``rtk``) profile, and each planned path is compared with the track's true
   centreline (distance of every path point to it). Targets: RMSE <= 0.10 m
   ideal, <= 0.25 m rtk. Views with no sound path (past the end of an open
   track) are counted, not scored.

Run: ``.venv/bin/python benchmarks/bench_planner.py [--quick]``.
"""

from __future__ import annotations

import argparse
import math
import os
import time

import numpy as np
from numpy.typing import NDArray

from conesim.core.messages import ConeDetections, Header
from conesim.core.pose import Pose2D
from conesim.localization.frames import Buffer, TransformStamped
from conesim.planner import (
    MidlineConfig,
    PathProjector,
    classify_cones_by_side,
    reference_path_planning,
)
from conesim.planner.classify import ClassifiedCones
from conesim.planner.midline import PlanStatus
from conesim.tracks.global_path import global_path_for_track, global_path_from_centreline

from timing import timed_calls

FloatArray = NDArray[np.float64]
VIEW = 30.0  # [m] cones ahead of the sensor in the latency scenes
SENSOR_Z = -0.1  # [m] os_sensor below gps_antenna (spec 000)


def frame_tree(pose: Pose2D, stamp: float = 1.0) -> Buffer:
    """A frame tree with ``gps_antenna`` at ``pose`` at ``stamp``."""
    buffer = Buffer()
    buffer.set_transform(TransformStamped.from_pose2d("reference", "gps_antenna", stamp, pose))
    buffer.set_transform_static(
        TransformStamped("gps_antenna", "os_sensor", 0.0, translation=(0.0, 0.0, SENSOR_Z))
    )
    return buffer


def winding_track(n_view: int, width: float = 3.5) -> tuple[FloatArray, FloatArray]:
    """Centreline (m, 2) of y = 4 sin(x / 8) over 200 m, and cones (k, 2) ~n_view per 30 m."""
    x = np.arange(0.0, 200.0, 0.5)  # 0.5 m apart, as the shipped global paths
    centre = np.column_stack([x, 4.0 * np.sin(x / 8.0)])
    t = np.gradient(centre, axis=0)
    t /= np.hypot(t[:, 0], t[:, 1])[:, None]
    normal = np.column_stack([-t[:, 1], t[:, 0]])
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(centre, axis=0).T))])
    spacing = 2.0 * VIEW * s[-1] / x[-1] / n_view
    at = np.arange(0.0, s[-1], spacing)
    pts = np.column_stack([np.interp(at, s, centre[:, k]) for k in range(2)])
    nrm = np.column_stack([np.interp(at, s, normal[:, k]) for k in range(2)])
    return centre, np.vstack([pts + 0.5 * width * nrm, pts - 0.5 * width * nrm])


def latency(
    n_view: int, repeats: int, scipy: dict[str, float] | None = None
) -> tuple[FloatArray, FloatArray, float, FloatArray, FloatArray]:
    """Per-detection times [ms] of classification and planning; mean cones in view.

    With ``scipy``, the tally of ``timing.timed_calls`` on the planner's
    scipy calls, also each detection's time in them [ms] and the points given
    to ``Delaunay`` (empty arrays without it).
    """
    centre, cones = winding_track(n_view)
    projector = PathProjector(global_path_from_centreline(centre, closed=False).polyline)
    config = MidlineConfig(max_range=VIEW + 2.0)
    t_cls, t_plan, seen, t_scipy, triangulated = [], [], [], [], []
    positions = np.linspace(10, len(centre) - 100, repeats).astype(int)
    for i in positions:
        d = centre[i + 1] - centre[i]
        pose = Pose2D(float(centre[i, 0]), float(centre[i, 1]), math.atan2(d[1], d[0]))
        local = pose.inverse_transform_points(cones)
        keep = (local[:, 0] > -2.0) & (local[:, 0] < VIEW)
        local = local[keep][np.argsort(np.hypot(*local[keep].T))]
        det = ConeDetections(
            Header(1.0, "os_sensor"), np.column_stack([local, np.zeros(len(local))])
        )
        buffer = frame_tree(pose)
        before = 0.0 if scipy is None else scipy["time"]
        t0 = time.perf_counter()
        classified = classify_cones_by_side(det, buffer, projector)
        t1 = time.perf_counter()
        plan = reference_path_planning(classified, buffer, config)
        t2 = time.perf_counter()
        assert plan.status is PlanStatus.OK, plan.reason
        t_cls.append(t1 - t0)
        t_plan.append(t2 - t1)
        seen.append(len(det))
        if scipy is not None:
            t_scipy.append(scipy["time"] - before)
            triangulated.append(len(plan.cones))
    return (
        1e3 * np.array(t_cls),
        1e3 * np.array(t_plan),
        float(np.mean(seen)),
        1e3 * np.array(t_scipy),
        np.array(triangulated, dtype=float),
    )


def scipy_floor(repeats: int) -> None:
    """Section 1b: the time in scipy's own calls per detection, and what it leaves.

    The planner's two scipy calls (``Delaunay`` on every cone in view and its
    virtual partners; ``splprep`` through the midpoints), which the issue and
    the ROS pipeline name, are timed where the planner makes them, in runs of the
    same scenes as section 1 with the timing wrappers added (the same data,
    the cache state of a planning step); "rest" is everything else per detection:
    the frame tree, the projection, the compiled steps, the messages.
    """
    import conesim.planner.bridges
    import conesim.planner.spline

    print("\n== scipy's own calls in the same runs (Delaunay, splprep) per detection [ms]")
    print(f"{'cones':>6} {'triangulated':>13} {'Delaunay mean':>13} {'splprep mean':>12} "
          f"{'scipy med':>10} {'rest med':>9} {'total med':>10}  "
          "target total med <= 0.5")  # fmt: skip
    targets = [(conesim.planner.bridges, "Delaunay"), (conesim.planner.spline, "splprep")]
    for n in (20, 40, 80):
        latency(n, 20)  # warm-up
        with timed_calls(targets) as tally:
            t_cls, t_plan, _, t_scipy, points = latency(n, repeats, tally)
        total = t_cls + t_plan
        calls = {name: max(tally[name], 1) for name in ("Delaunay", "splprep")}
        per_call = {name: 1e3 * tally[f"{name}_time"] / calls[name] for name in calls}
        floor = float(np.median(t_scipy))
        print(f"{n:>6} {np.mean(points):>13.1f} {per_call['Delaunay']:>13.3f} "
              f"{per_call['splprep']:>12.3f} {floor:>10.3f} {np.median(total - t_scipy):>9.3f} "
              f"{np.median(total):>10.3f}  scipy alone leaves {0.5 - floor:+.3f} "
              "for the rest")  # fmt: skip


def distance_to_polyline(points: FloatArray, line: FloatArray, closed: bool) -> FloatArray:
    """(n,) distance of each point to the polyline [m] (brute force)."""
    ring = np.vstack([line, line[:1]]) if closed else line
    a, d = ring[:-1], np.diff(ring, axis=0)
    rel = points[:, None, :] - a[None]
    t = np.clip(np.einsum("mki,ki->mk", rel, d) / np.einsum("ki,ki->k", d, d), 0.0, 1.0)
    gap = rel - t[..., None] * d[None]
    return np.sqrt(np.min(np.einsum("mki,mki->mk", gap, gap), axis=1))


def accuracy(track_name: str, profile_name: str, step: int) -> tuple[float, float, int, int]:
    """RMSE and max [m] of the planned paths over a lap, with views scored and not."""
    from conesim.sim.sensors.cone_detector import ConeDetector
    from conesim.sim.sensors.profiles import get_profile
    from conesim.sim.sensors.truth import TruthSample
    from conesim.tracks import load_track

    track = load_track(track_name)
    path = global_path_for_track(track)
    projector = PathProjector(path.polyline)
    detector = ConeDetector(get_profile(profile_name).cones, seed=0)
    kinds = tuple(str(k) for k in track.kinds)
    closed = str(track.layout) == "closed"
    centre = np.asarray(track.centreline)
    errors, unscored = [], 0
    hint: float | None = None
    xy = path.xy
    for k in range(0, len(xy), step):
        ahead = (
            xy[(k + 1) % len(xy)] - xy[k] if k + 1 < len(xy) or path.closed else xy[k] - xy[k - 1]
        )
        pose = Pose2D(float(xy[k, 0]), float(xy[k, 1]), math.atan2(ahead[1], ahead[0]))
        buffer = frame_tree(pose)
        truth = TruthSample(
            t=1.0, antenna_pose=pose, cone_positions=np.asarray(track.cones), cone_kinds=kinds
        )
        classified: ClassifiedCones = classify_cones_by_side(
            detector.capture(truth), buffer, projector, station_hint=hint
        )
        hint = classified.sensor_station
        plan = reference_path_planning(classified, buffer)
        if plan.status is not PlanStatus.OK:
            unscored += 1
            continue
        in_reference = buffer.transform_points("reference", "os_sensor", plan.path, 1.0)
        errors.append(distance_to_polyline(in_reference, centre, closed))
    e = np.concatenate(errors)
    return float(np.sqrt(np.mean(e**2))), float(e.max()), len(errors), unscored


def main() -> None:
    """Run both benchmarks and print their figures."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer repeats and views")
    args = parser.parse_args()
    repeats = 100 if args.quick else 400

    load = " ".join(f"{x:.2f}" for x in os.getloadavg())
    print(f"== planning latency per detection (classify + plan + speed profile) [ms], "
          f"load average {load}")  # fmt: skip
    print(f"{'cones':>6} {'in view':>8} {'classify med':>13} {'plan med':>9} "
          f"{'total med':>10} {'total p99':>10}  targets: med <= 0.5, p99 <= 2")  # fmt: skip
    for n in (20, 40, 80):
        latency(n, 20)  # warm-up
        t_cls, t_plan, seen, _, _ = latency(n, repeats)
        total = t_cls + t_plan
        print(f"{n:>6} {seen:>8.1f} {np.median(t_cls):>13.3f} {np.median(t_plan):>9.3f} "
              f"{np.median(total):>10.3f} {np.percentile(total, 99):>10.3f}")  # fmt: skip
    scipy_floor(repeats)

    print("\n== midline accuracy against the true centreline, one lap of views [m]")
    print(f"{'track':>13} {'detector':>9} {'RMSE':>7} {'max':>6} {'views':>6} {'no path':>8}"
          "  targets: RMSE <= 0.10 ideal, <= 0.25 rtk")  # fmt: skip
    try:
        from conesim.tracks import shipped_tracks
    except ImportError as exc:  # pragma: no cover - tracks is part of the package
        print(f"  skipped: {exc}")
        return
    step = 4 if args.quick else 2  # global path points are 0.5 m apart: a view per metre
    for name in shipped_tracks():
        for profile in ("ideal", "rtk"):
            rmse, worst, scored, unscored = accuracy(name, profile, step)
            print(f"{name:>13} {profile:>9} {rmse:>7.3f} {worst:>6.3f} {scored:>6} {unscored:>8}")


if __name__ == "__main__":
    main()
