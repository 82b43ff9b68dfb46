"""Localization against the cone map (issue 16, ``cones``): accuracy, clean laps, cost.

Every shipped track and ``--generated`` generated tracks (``generate_track``,
medium, seeds ``--first`` on; 3000 and up stay clear of the seeds used for
tuning), 2 laps each (an open lane is one run), seed 0, with:

* ``consumer`` GPS (a u-blox M8: about 2 m of slowly varying error) with
  ``fused`` (no map) and ``cones`` (the map, surveyed with its default
  error: 3 cm per cone, a 2 cm bias);
* ``rtk`` with both (cones must be no worse);
* ``consumer`` with ``cones`` under the issue's faults: 30 % of the cones
  missed, 1 false positive per scan, 5 % blue / yellow swaps.

Per configuration it prints the position and heading RMSE of the published
pose against the truth (the RMS over all runs of each run's RMSE, and the
worst run), the share of clean runs (every lap, no cone down or out, no
off-track event), the real-time factor (simulated over wall time, summed
over the runs; the worker processes run side by side), and, with the map,
the association counts per scan and the cone updates' NIS: its mean over
the degrees of freedom (1 when consistent) and the share of scans inside
their two-sided 95 % chi-square band. The cost target compares the
real-time factor with the cone updates to the one without, on the same
tracks with the same GPS; a bare pymunk reference is printed beside it
(``timing.pymunk_reference``).

Run: ``.venv/bin/python benchmarks/bench_cone_localization.py [--generated N]
[--first S] [--jobs J]`` (J worker processes, default 2; about 2-5 s of wall
time per run on one core).
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable, Iterable
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from typing import TypeVar

from conesim.envs.runner import run_scenario
from conesim.envs.scenario import Scenario
from conesim.sim.sensors import Faults, get_profile
from conesim.sim.sensors.faults import ConeFaults
from conesim.tracks import GeneratedTrack, TrackSpec, shipped_tracks

from timing import pymunk_reference

FAULTS = Faults(
    cones=ConeFaults(
        detection_probability=0.7, false_positives_per_scan=1.0, colour_swap_probability=0.05
    )
)
CONFIGS = {
    "consumer fused": ("consumer", "fused", Faults()),
    "consumer cones": ("consumer", "cones", Faults()),
    "rtk fused": ("rtk", "fused", Faults()),
    "rtk cones": ("rtk", "cones", Faults()),
    "consumer cones faults": ("consumer", "cones", FAULTS),
}
R = TypeVar("R")
TARGETS = "targets: consumer cones RMSE <= 0.20 m, <= 0.5 deg, clean >= 95 %; faults clean >= 90 %"


@dataclass(frozen=True)
class Run:
    """One run's figures."""

    track: str
    config: str
    clean: bool
    end: str
    pos_rmse: float
    yaw_rmse: float
    sim_time: float
    wall_time: float
    cones: dict[str, float] | None


def one_run(job: tuple[str | GeneratedTrack, str]) -> Run:
    """Drive one track with one configuration."""
    track, config = job
    sensors, localization, faults = CONFIGS[config]
    scenario = Scenario(
        track=track, laps=2, seed=0, sensors=get_profile(sensors),
        localization=localization, faults=faults,  # type: ignore[arg-type]
    )  # fmt: skip
    r = run_scenario(scenario)
    name = track.name if isinstance(track, GeneratedTrack) else track
    return Run(
        name, config, r.clean, r.end_reason,
        math.inf if r.localization_pos_rmse_m is None else r.localization_pos_rmse_m,
        math.inf if r.localization_yaw_rmse_deg is None else r.localization_yaw_rmse_deg,
        r.sim_time_s, r.wall_time_s, r.cone_associations,
    )  # fmt: skip


def rms(values: list[float]) -> float:
    """Root mean square."""
    return math.sqrt(sum(v * v for v in values) / len(values))


def report(config: str, rows: list[Run]) -> float:
    """Print one configuration's line (and its counts); its real-time factor."""
    clean = sum(r.clean for r in rows)
    rtf = sum(r.sim_time for r in rows) / sum(r.wall_time for r in rows)
    pos, yaw = [r.pos_rmse for r in rows], [r.yaw_rmse for r in rows]
    bad = ", ".join(f"{r.track}:{r.end}" for r in rows if not r.clean) or "-"
    print(
        f"  {config:22s} {rms(pos):6.3f} {max(pos):6.3f}  {rms(yaw):5.2f} {max(yaw):5.2f}  "
        f"{100.0 * clean / len(rows):5.1f} %  {rtf:5.1f}x  {bad}"
    )
    return rtf


def counts(config: str, rows: list[Run]) -> None:
    """Print a map configuration's association counts and NIS."""
    total: dict[str, float] = {}
    for r in rows:
        for k, v in (r.cones or {}).items():
            total[k] = total.get(k, 0.0) + v
    scans = total.get("scans", 0.0)
    if not scans:
        return
    used = scans - total["scans_gated"]
    per = {
        k: total[k] / scans
        for k in ("matched", "false_positives", "colour_mismatches", "ambiguous", "misses")
    }
    print(
        f"  {config:22s} per scan: " + ", ".join(f"{k} {v:.2f}" for k, v in per.items())
        + f"; scans gated {int(total['scans_gated'])} of {int(scans)}; "
        f"NIS/dof {total['nis_sum'] / total['dof_sum']:.3f}, "
        f"in 95 % band {100.0 * total['nis_in_band'] / used:.1f} %"
    )  # fmt: skip


def drive_all(
    doc: str,
    configs: Iterable[str],
    run: Callable[[tuple[str | GeneratedTrack, str]], R],
    *,
    generated: int,
    first: int,
    jobs: int,
) -> tuple[argparse.Namespace, list[R], float, float]:
    """Parse the options, run every track with every configuration in ``jobs`` worker
    processes; (the options, the runs, bare pymunk's steps/s before and after)."""
    parser = argparse.ArgumentParser(description=doc.splitlines()[0])
    parser.add_argument("--generated", type=int, default=generated, help="generated tracks")
    parser.add_argument("--first", type=int, default=first, help="first generated seed")
    parser.add_argument("--jobs", type=int, default=jobs, help="worker processes")
    args = parser.parse_args()
    seeds = range(args.first, args.first + args.generated)
    tracks: list[str | GeneratedTrack] = [
        *shipped_tracks(),
        *(GeneratedTrack(s, TrackSpec()) for s in seeds),
    ]
    before = pymunk_reference()
    with ProcessPoolExecutor(max(1, args.jobs)) as pool:
        results = list(pool.map(run, [(t, c) for t in tracks for c in configs]))
    return args, results, before, pymunk_reference()


def header(title: str, args: argparse.Namespace, width: int) -> None:
    """The tracks run and the table's head, its first column ``width`` wide."""
    last = args.first + args.generated - 1
    print(
        f"{title}: {len(shipped_tracks())} shipped tracks + generated "
        f"{args.first}-{last} (medium), 2 laps, seed 0, {args.jobs} workers"
    )
    print(f"  {'configuration':{width}s} pos RMSE [m]   yaw [deg]    clean    RTF    not clean")
    print(f"  {'':{width}s} rms    worst   rms   worst")


def main() -> None:
    """Print the figures."""
    args, results, before, after = drive_all(
        __doc__, CONFIGS, one_run, generated=6, first=3000, jobs=2
    )
    header("cone-map localization", args, 22)
    rtf = {c: report(c, [r for r in results if r.config == c]) for c in CONFIGS}
    for c in CONFIGS:
        counts(c, [r for r in results if r.config == c])
    for gps in ("consumer", "rtk"):
        ratio = rtf[f"{gps} cones"] / rtf[f"{gps} fused"]
        print(f"  cost, {gps}: real-time factor with cone updates / without = {ratio:.2f}")
    print(f"  bare pymunk: {before:,.0f} steps/s before, {after:,.0f} after")
    print(f"  {TARGETS}; rtk no worse with cones; cost ratio >= 0.7")


if __name__ == "__main__":
    main()
