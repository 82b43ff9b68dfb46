"""The lap-time limit held against the physics. Prints figures.

For each track of a list (default: the shipped ones; any track file works,
so generated tracks can be checked the same way):

1. **The limit**: ``limit_lap_time_s`` (the racing line's QSS lap,
   ``envs.limit_lap``), the centreline's figure, their ratio, the racing
   line's blend, and what computing it costs (median of ``--repeat`` cold
   computations, the cache cleared each time).
2. **The racing line driven**: the simulated car with truth localization
   and ideal sensors follows the racing line itself (``line_steering``: the
   line's curvature fed forward, the CG's offset and course error fed
   back); the speed is ``--speed-factor`` times the line's QSS speed, read
   a little ahead of the car for the actuators' lag, held by a PI
   controller with the profile's acceleration fed forward.
   Its best flying lap must not beat the limit by more than 1 %; how far
   above it lies says how conservative the limit is.
3. **The autopilot** (``--autopilot``): ``conesim run`` with rtk sensors
   and fused localization, ``--laps`` laps, ``--seeds`` seeds, each in a
   process of its own (a run that crashes is reported): no clean lap may
   beat the limit by more than 1 %.

Run: ``.venv/bin/python benchmarks/bench_limit.py [--tracks a,b,FILE]
[--hand-made DIR] [--speed-factor 0.9,1.0] [--autopilot] [--seeds N]
[--laps N]`` (``--hand-made``: also ``limit_tracks.py``'s rings, hairpins
and S-bend, written to DIR). Exit status 1 when a lap beats the limit by
more than 1 %.
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from limit_tracks import write_hand_made

from conesim.core.polyline import Polyline
from conesim.core.pose import Pose2D
from conesim.core.projection import Projection
from conesim.envs import limit_lap
from conesim.envs.limit_lap import (
    FloatArray,
    centreline_grid,
    qss_speed_profile,
    track_lap_limit,
)
from conesim.envs.loop import ClosedLoop, EpisodeRules
from conesim.planner.messages import ControlCommand
from conesim.sim.vehicle import VehicleState
from conesim.sim.vehicle_params import VehicleParams
from conesim.sim.world import WorldConfig
from conesim.tracks import Track, load_track, shipped_tracks

BEATEN_BY = 0.01  # a lap more than 1 % below the limit fails the check
PREVIEW_S = 0.15  # [s] the target speed is read this far ahead of the car
STEER_PREVIEW_S = 0.1  # [s] the curvature fed forward is read this far ahead
SPEED_GAIN = 2.0  # [1/s] proportional speed control
SPEED_INTEGRAL_GAIN = 1.0  # [1/s^2] its integral (the tyres' cornering drag)
W_DISTANCE = 0.5  # [1/m] the lateral error's natural frequency per metre, at most
W_TIME = 3.0  # [rad/s] and per second (the steering's rate limit and lag)
ZETA = 0.9  # [-] its damping
YAW_DAMPING = 0.05  # [s] steering per yaw rate beyond the line's (a stability aid)


@dataclass(frozen=True)
class LineRun:
    """One drive along the racing line."""

    laps: list[float]  # flying laps, timed where the line starts
    cones_down: int
    off_track: int
    end: str
    worst_offset_m: float  # the CG's largest distance from the line after the first lap


def drive_racing_line(track: Track, speed_factor: float, laps: int = 3) -> LineRun:
    """Drive ``track``'s racing line at ``speed_factor`` times its QSS speed (module doc)."""
    p = VehicleParams()
    line = track_lap_limit(track, p).racing_line
    if line is None:
        raise ValueError(f"{track.name}: no racing line (an open lane)")
    s, kappa = centreline_grid(line, True)
    v_qss = qss_speed_profile(s, kappa, True, p) * speed_factor
    ring = Polyline(line, True)
    length = ring.end_station
    dv2 = np.gradient(np.concatenate([v_qss, v_qss[:1]]) ** 2)[:-1]
    a_ff = 0.5 * dv2 / np.gradient(s)  # the profile's acceleration [m/s^2]
    loop = ClosedLoop(
        track,
        WorldConfig(sensors="ideal", vehicle=p),
        localization="truth",
        # Race control's laps are the track's (the skidpad's a figure of eight):
        # the laps here are timed where the line starts, so no end but the time.
        rules=EpisodeRules(laps=100, time_limit=60.0 * (laps + 1), end_on_stuck=False),
    )
    heading = ring.tangents()[0]
    start = Pose2D(float(line[0, 0]), float(line[0, 1]), math.atan2(heading[1], heading[0]))
    record = loop.reset(seed=0, start_pose=start)  # on the line (the skidpad's circle)
    dt = 1.0 / loop.control_rate
    worst, previous, integral = 0.0, 0.0, 0.0
    wraps: list[float] = []
    while record.end is None and len(wraps) <= laps:
        st = record.truth.state
        speed = math.hypot(st.vx, st.vy)
        proj = ring.project(np.array([st.x, st.y]))
        station = float(proj.station[0])
        if previous > length - 5.0 and station < 5.0:  # past the line's start
            wraps.append(record.t)
        previous = station
        if wraps:
            worst = max(worst, abs(float(proj.lateral[0])))
        steer = line_steering(st, speed=speed, proj=proj, s=s, kappa=kappa, length=length, p=p)
        preview = (station + speed * PREVIEW_S) % length
        target = float(np.interp(preview, s, v_qss, period=length))
        feed = float(np.interp(preview, s, a_ff, period=length))
        error = target - speed
        accel = feed + SPEED_GAIN * error + SPEED_INTEGRAL_GAIN * integral
        if -p.max_decel < accel < p.max_accel:  # no wind-up at the actuator's limits
            integral += error * dt
        accel = min(max(accel, -p.max_decel), p.max_accel)
        record = loop.step(ControlCommand(record.t + dt, steer, accel))
    race = record.truth.race
    return LineRun(
        [float(b - a) for a, b in itertools.pairwise(wraps)],
        race.cones_down_or_out,
        race.off_track_events,
        "laps_completed" if len(wraps) > laps else str(record.end),
        worst,
    )


def line_steering(
    st: VehicleState,
    *,
    speed: float,
    proj: Projection,
    s: FloatArray,
    kappa: FloatArray,
    length: float,
    p: VehicleParams,
) -> float:
    """Front wheel angle [rad]: the line's curvature fed forward (L kappa: the car
    steers neutrally, lf = lr and one tyre), and the CG's offset e and course error
    chi fed back, delta = L kappa - L w^2 e - 2 zeta L w chi: a second-order
    lateral error with w = min(W_DISTANCE, W_TIME / v) per metre; and the yaw
    rate beyond the line's, r - v kappa, damped (braking into a corner the
    unloaded rear lets go first)."""
    preview = (float(proj.station[0]) + speed * STEER_PREVIEW_S) % length
    k_ref = float(np.interp(preview, s, kappa, period=length))
    tangent = proj.tangent[0]
    course = st.yaw + (math.atan2(st.vy, st.vx) if speed > 1.0 else 0.0)
    chi = math.remainder(course - math.atan2(tangent[1], tangent[0]), math.tau)
    w = min(W_DISTANCE, W_TIME / max(speed, 1.0))
    lat = float(proj.lateral[0])
    delta = math.atan(p.wheelbase * k_ref) - p.wheelbase * w * (w * lat + 2 * ZETA * chi)
    delta -= YAW_DAMPING * (st.yaw_rate - speed * k_ref)  # counter-steer a rotating car
    return min(max(delta, -p.max_steer), p.max_steer)


def autopilot_run(track: str, laps: int, seed: int) -> dict[str, Any] | None:
    """``conesim run`` (rtk, fused) in a process of its own, so that a crash of
    one run is reported, not fatal; its result.json, or None if it crashed."""
    with tempfile.TemporaryDirectory() as out:
        done = subprocess.run(
            [
                sys.executable, "-m", "conesim", "run", "--track", track, "--laps", str(laps),
                "--seed", str(seed), "--json", "--out", str(Path(out) / "run"),
            ],
            capture_output=True, text=True, check=False,
        )  # fmt: skip
    if done.returncode not in (0, 1):
        sys.stderr.write(done.stderr[-2000:])
        return None
    result: dict[str, Any] = json.loads(done.stdout)
    return result


def limit_cost(track: Track, repeat: int) -> float:
    """Median wall time of computing the limit from scratch [s]."""
    times = []
    for _ in range(repeat):
        limit_lap._LIMITS.clear()
        t0 = time.perf_counter()
        track_lap_limit(track)
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main() -> int:
    """Print the figures; 1 when a lap beats a limit by more than 1 %."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tracks", default=",".join(shipped_tracks()), help="names or files")
    parser.add_argument("--speed-factor", default="0.9,0.95,1.0", help="shares of the QSS speed")
    parser.add_argument("--repeat", type=int, default=5, help="cold computations timed")
    parser.add_argument("--autopilot", action="store_true", help="also run the autopilot")
    parser.add_argument("--seeds", type=int, default=1, help="autopilot seeds per track")
    parser.add_argument("--laps", type=int, default=2, help="autopilot laps")
    parser.add_argument(
        "--hand-made", metavar="DIR", help="also write limit_tracks' loops to DIR and run them"
    )
    args = parser.parse_args()
    try:
        factors = [float(f) for f in args.speed_factor.split(",") if f.strip()]
        names = [t.strip() for t in args.tracks.split(",") if t.strip()]
        if args.hand_made:
            names += [str(path) for path in write_hand_made(Path(args.hand_made))]
        tracks = [load_track(name) for name in names]
    except (ValueError, OSError) as exc:
        print(f"bench_limit: error: {exc}", file=sys.stderr)
        return 2
    failed = False
    print("1. the limit: racing line against centreline (QSS), and its cost")
    print(f"  {'track':14s} {'limit':>8s} {'centre':>8s} {'ratio':>6s} {'blend':>5s} {'cost':>8s}")
    for track in tracks:
        lim = track_lap_limit(track)
        blend = "-" if lim.blend is None else f"{lim.blend:.3f}"
        cost = limit_cost(track, args.repeat)
        print(
            f"  {track.name:14s} {lim.limit_s:7.3f}s {lim.centreline_s:7.3f}s "
            f"{lim.limit_s / lim.centreline_s:6.3f} {blend:>5s} {cost * 1e3:6.0f}ms"
        )
    print("\n2. the racing line driven (ideal sensors, truth localization, 3 laps)")
    print(f"  {'track':14s} {'factor':>6s} {'best':>8s} {'/limit':>7s}  laps, DOO, off, end")
    for track in tracks:
        lim = track_lap_limit(track)
        if lim.racing_line is None:
            print(f"  {track.name:14s} (an open lane: its limit is the centreline's)")
            continue
        for factor in factors:
            run = drive_racing_line(track, factor)
            best = min(run.laps) if run.laps else math.nan
            ratio = best / lim.limit_s
            failed |= ratio < 1.0 - BEATEN_BY
            laps = ", ".join(f"{t:.2f}" for t in run.laps)
            print(
                f"  {track.name:14s} {factor:6.2f} {best:7.3f}s {ratio:7.3f}  "
                f"[{laps}], {run.cones_down}, {run.off_track}, {run.end}"
            )
    if args.autopilot:
        print(f"\n3. the autopilot (rtk, fused, {args.laps} laps, {args.seeds} seeds)")
        print(f"  {'track':14s} {'seed':>4s} {'best':>8s} {'/limit':>7s}  clean, laps")
        for name, track in zip(names, tracks, strict=True):
            lim = track_lap_limit(track)
            for seed in range(args.seeds):
                r = autopilot_run(name, args.laps, seed)
                if r is None:
                    print(f"  {track.name:14s} {seed:4d}  the run crashed (see its stderr)")
                    continue
                clean = r["finished"] and r["cones_down_or_out"] == 0 and not r["off_track_events"]
                best_lap = math.nan if r["best_lap_s"] is None else r["best_lap_s"]
                ratio = best_lap / lim.limit_s
                failed |= clean and ratio < 1.0 - BEATEN_BY
                laps = ", ".join(f"{t:.2f}" for t in r["lap_times_s"])
                print(
                    f"  {track.name:14s} {seed:4d} {best_lap:7.3f}s {ratio:7.3f}  "
                    f"{'yes' if clean else 'no'}, [{laps}]"
                )
    print(f"\nno lap beats its limit by more than {BEATEN_BY:.0%}: {'no' if failed else 'yes'}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
