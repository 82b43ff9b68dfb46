"""Localization with a map built on the first lap (issue 16, ``slam``): map, laps, NIS, cost.

Every shipped track and ``--generated`` generated tracks (medium, seeds
``--first`` on; 6000 and up, apart from the seeds used for tuning, < 100 in
the tests), 2 laps each (an open lane is one run), seed 0, with:

* ``consumer`` GPS (a u-blox M8: about 2 m of slowly varying error) with
  ``fused`` (no map), ``cones`` (the surveyed map, for reference) and
  ``slam`` (the map built on lap 1, frozen when the loop closes).

Per configuration: the pose RMSE against the truth (RMS over the runs of
each run's RMSE, and the worst run), the share of clean runs, the real-time
factor (simulated over wall time, summed over the runs), and the runs not
clean. For ``slam`` also:

* the map right after lap 1 (``result.json``'s ``map_quality``): its mean
  error against the true cones raw (in ``reference``, as the issue asks)
  and with the best rigid fit removed (its shape), per run averaged, the
  worst run's mean, the worst single cone; missed true cones and spurious
  landmarks, summed; the map's NEES per dof;
* clean second laps: of the runs that have a second lap (not the open
  lane), those that complete it with no cone down or out and no off-track
  event during it;
* the cone updates' NIS (``bench_cone_localization.counts``).

The cost compares the real-time factor with slam to fused's on the same
tracks and GPS, a bare pymunk reference beside it (``timing``).

Run: ``.venv/bin/python benchmarks/bench_slam.py [--generated N] [--first S]
[--jobs J]`` (default 16 tracks from 6000, 1 worker: slam runs take 5-10 s
of wall time each on one core).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from bench_cone_localization import counts, drive_all, header, report

from conesim.envs.runner import RunResult, run_scenario
from conesim.envs.scenario import Scenario
from conesim.sim.sensors import get_profile
from conesim.tracks import GeneratedTrack

CONFIGS = {
    "consumer fused": ("consumer", "fused"),
    "consumer cones": ("consumer", "cones"),
    "consumer slam": ("consumer", "slam"),
}
TARGETS = "targets: consumer slam map error <= 0.3 m per cone, clean second laps >= 90 %"


@dataclass(frozen=True)
class Run:
    """One run's figures."""

    track: str
    config: str
    clean: bool
    second_lap: bool | None  # None: no second lap to drive (an open lane)
    end: str
    pos_rmse: float
    yaw_rmse: float
    sim_time: float
    wall_time: float
    cones: dict[str, float] | None
    map_quality: dict[str, float] | None


def second_lap_clean(r: RunResult) -> bool | None:
    """Lap 2 completed with no cone down or out and no excursion during it; None without one."""
    if r.laps < 2:
        return None
    laps = {lap.lap: lap.t for lap in r.events.laps}
    if 2 not in laps:
        return False
    start, end = laps.get(1, 0.0), laps[2]
    downs = [c for c in r.events.cones_down_or_out if start <= c.t <= end]
    off = [e for e in r.events.off_track if start <= e.t_start <= end]
    return not downs and not off


def one_run(job: tuple[str | GeneratedTrack, str]) -> Run:
    """Drive one track with one configuration."""
    track, config = job
    sensors, localization = CONFIGS[config]
    scenario = Scenario(
        track=track, laps=2, seed=0, sensors=get_profile(sensors),
        localization=localization,  # type: ignore[arg-type]
    )  # fmt: skip
    r = run_scenario(scenario)
    name = track.name if isinstance(track, GeneratedTrack) else track
    return Run(
        name, config, r.clean, second_lap_clean(r), r.end_reason,
        math.inf if r.localization_pos_rmse_m is None else r.localization_pos_rmse_m,
        math.inf if r.localization_yaw_rmse_deg is None else r.localization_yaw_rmse_deg,
        r.sim_time_s, r.wall_time_s, r.cone_associations, r.map_quality,
    )  # fmt: skip


def map_report(config: str, rows: list[Run]) -> None:
    """Print a slam configuration's map after lap 1 and its clean second laps."""
    maps = [r.map_quality for r in rows if r.map_quality is not None]
    second = [r for r in rows if r.second_lap is not None]
    good = [r for r in second if r.second_lap]
    failed = ", ".join(r.track for r in second if not r.second_lap) or "-"
    if maps:
        raw = [q["mean_error_m"] for q in maps]
        aligned = [q["mean_error_aligned_m"] for q in maps]
        within = sum(q["mean_error_m"] <= 0.3 for q in maps)
        print(
            f"  {config:16s} map after lap 1 ({len(maps)} runs): mean error raw "
            f"{sum(raw) / len(raw):.3f} m (worst run {max(raw):.3f}, worst cone "
            f"{max(q['max_error_m'] for q in maps):.3f}), rigid fit removed "
            f"{sum(aligned) / len(aligned):.3f} m (worst run {max(aligned):.3f}); runs with "
            f"mean <= 0.3 m: {within}/{len(maps)}; missed {sum(q['missed'] for q in maps):.0f} "
            f"and spurious {sum(q['spurious'] for q in maps):.0f} of "
            f"{sum(q['cones'] for q in maps):.0f} cones; map NEES/dof "
            f"{sum(q['nees_per_dof'] for q in maps) / len(maps):.2f}"
        )
    if second:
        print(
            f"  {config:16s} clean second laps: {len(good)}/{len(second)} "
            f"({100.0 * len(good) / len(second):.1f} %); not: {failed}"
        )


def main() -> None:
    """Print the figures."""
    args, results, before, after = drive_all(
        __doc__, CONFIGS, one_run, generated=16, first=6000, jobs=1
    )
    header("slam localization", args, 16)
    rtf = {c: report(c, [r for r in results if r.config == c]) for c in CONFIGS}  # type: ignore[misc]
    for c in CONFIGS:
        rows = [r for r in results if r.config == c]
        counts(c, rows)  # type: ignore[arg-type]
        map_report(c, rows)
    for gps in ("consumer", "rtk"):
        if f"{gps} fused" in rtf:
            ratio = rtf[f"{gps} slam"] / rtf[f"{gps} fused"]
            print(f"  cost, {gps}: real-time factor with slam / fused = {ratio:.2f}")
    print(f"  bare pymunk: {before:,.0f} steps/s before, {after:,.0f} after")
    print(f"  {TARGETS}")


if __name__ == "__main__":
    main()
