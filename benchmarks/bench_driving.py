"""Whether the autopilot drives clean on generated tracks it has never seen (issue 15).

``--tracks`` tracks from the random generator (``conesim.tracks.generate``),
seeds ``--first`` on, a third each of the three sizes (small, medium, large
by seed), 2 laps each, fused localization, with three sensor profiles:
``ideal``, ``rtk``, and ``harsh`` (rtk with 30 % of the cones missed, 1
false positive per scan, 5 % blue / yellow swaps and a 5 s GPS dropout,
10-15 s). The runs are a sweep (``conesim sweep``) into a new temporary
directory, or into ``--out DIR`` (its file beside it as DIR.sweep.yaml),
where the same command resumes an interrupted benchmark; runs already there
are not run again, so give a new DIR after changing the code. Per profile
it prints the clean share (all laps, no cone down or out, no off-track
event), the flying lap (lap 2) against the track's ``limit_lap_time_s``
(min, median, max over the clean runs) and against the midline's speed
plan (``plan_lap_time``: the median; the racing line laps below it),
cones down or out per km
driven, and the runs that were not clean. A last line says where the
ratio to the limit comes from: the centreline driven at the car's limits
(``centreline_lap_time_s``) and the autopilot's plan (the centreline at
the planner's limits, ``SpeedProfileConfig``), each over the limit.

A seed that makes no track (the generator gives up on a few large ones)
is left out, and said so. Seeds: the tests drive generated seeds below 100,
tuning used seeds 1000-1339, then 5000-5199 and 7000-7199 (earlier
held-out sets, looked at once their figures were in), and 9000-9199's
failures were looked at (they showed the racing line's gate bug), 9200-9399
reported the racing line at the midline's speed limits, 9400-9599 at its
own (their failures were looked at: the feed-forward's preview), 9600-9799
its preview 0.12 s, 9800-9999 the speed controller reading the line's
curvature; the next held-out report uses seeds 10000 on.
``--set KEY=VALUE`` (as ``conesim run --set``) changes the base scenario,
for a before / after comparison.

Run: ``.venv/bin/python benchmarks/bench_driving.py [--tracks N] [--first S]
[--workers J] [--profiles ideal,rtk,harsh] [--out DIR] [--set KEY=VALUE]``
(about 3 s of one core per run).
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from conesim.envs.scenario_file import Override, apply_override, scenario_from_mapping
from conesim.envs.sweep import run_sweep
from conesim.envs.sweep_file import BASE_LABEL, load_sweep
from conesim.envs.sweep_store import read_rows
from conesim.envs.yaml_io import dump_yaml, parse_value
from conesim.planner.config import AutopilotConfig, SpeedProfileConfig
from conesim.planner.global_fit import smoothed_global_path
from conesim.planner.global_speed import GlobalSpeedPlan
from conesim.planner.lap_map import lap_time
from conesim.tracks import Track
from conesim.tracks.generate import Size, TrackGenerationError, TrackSpec, generate_track
from conesim.tracks.global_path import global_path_for_track

SIZES: tuple[Size, ...] = ("small", "medium", "large")
HARSH = {
    "cones": {
        "detection_probability": 0.7,
        "false_positives_per_scan": 1.0,
        "colour_swap_probability": 0.05,
    },
    "gps": {"dropouts": [[10.0, 15.0]]},
}
PROFILES: dict[str, dict[str, Any]] = {
    "ideal": {"sensors.profile": "ideal"},
    "rtk": {"sensors.profile": "rtk"},
    "harsh": {"sensors.profile": "rtk", "faults": HARSH},
}


def sweep_file(seeds: list[int], profiles: list[str], settings: list[str]) -> dict[str, Any]:
    """The benchmark's sweep: every seed (its size by seed) with every profile."""
    base: dict[str, Any] = {
        "conesim_scenario": 1,
        "track": {"generate": {"seed": seeds[0], "size": "small"}},
        "laps": 2,
        "seed": 0,
    }
    for setting in settings:
        key, _, text = setting.partition("=")
        apply_override(base, Override(key, parse_value(text), f"--set {setting}"))
    points = [
        {"track.generate.seed": s, "track.generate.size": SIZES[s % 3], "profile": p} | PROFILES[p]
        for s in seeds
        for p in profiles
    ]
    # "profile" is a label only: drop it, the sweep takes scenario keys alone
    for point in points:
        del point["profile"]
    return {"conesim_sweep": 1, "base": base, "points": points}


def profile_of(row: dict[str, Any]) -> str:
    """Which of ``PROFILES`` a results row ran."""
    axes = row["axes"]
    if axes.get("sensors.profile") == "ideal":
        return "ideal"
    return "harsh" if axes.get("faults", BASE_LABEL) != BASE_LABEL else "rtk"


def main() -> None:
    """Run (or resume) the sweep and print the figures."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tracks", type=int, default=200, help="tracks (seeds)")
    parser.add_argument("--first", type=int, default=10000, help="first seed")
    parser.add_argument("--workers", type=int, default=None, help="processes (all cores)")
    parser.add_argument("--profiles", default=",".join(PROFILES))
    parser.add_argument("--out", default=None, help="the sweep's directory (resumable)")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    args = parser.parse_args()
    profiles = [p.strip() for p in args.profiles.split(",") if p.strip()]
    seeds = range(args.first, args.first + args.tracks)
    with tempfile.TemporaryDirectory(prefix="bench-driving-") as tmp:
        out = Path(args.out) if args.out else Path(tmp) / "sweep"
        out.mkdir(parents=True, exist_ok=True)
        report(out, seeds, profiles, args)


def plan_lap_time(track: Track, config: SpeedProfileConfig) -> float:
    """The autopilot's own speed plan's flying lap [s]: ``GlobalSpeedPlan`` (the
    centreline at the planner's limits) on the global path as the autopilot
    smooths it, timed as ds over the mean speed of each step."""
    path = smoothed_global_path(
        global_path_for_track(track), AutopilotConfig().global_path_min_scatter
    )
    return lap_time(GlobalSpeedPlan(path, config))


def track_laps(seeds: range, config: SpeedProfileConfig) -> dict[int, tuple[float, float]]:
    """Each seed's lap length [m] and ``plan_lap_time`` [s], without the seeds that
    make no track (said on stdout)."""
    laps = {}
    for s in seeds:
        try:
            track = generate_track(s, TrackSpec(size=SIZES[s % 3]))
        except TrackGenerationError as exc:
            print(f"  left out: {exc}")
            continue
        laps[s] = (track.length_m, plan_lap_time(track, config))
    return laps


def spread(values: list[float]) -> str:
    """min, median and max of ``values``, or n/a."""
    if not values:
        return "n/a"
    return f"{min(values):.3f} {float(np.median(values)):.3f} {max(values):.3f}"


def report(out: Path, seeds: range, profiles: list[str], args: argparse.Namespace) -> None:
    """Run (or resume) the sweep into ``out`` and print the figures."""
    sweep = sweep_file(list(seeds), profiles, args.set)
    planning = scenario_from_mapping(sweep["base"]).autopilot_config().speed_profile
    laps = track_laps(seeds, planning)
    if not laps:
        print("  no track to drive")
        return
    spec_file = out.with_name(out.name + ".sweep.yaml")
    spec_file.write_text(dump_yaml(sweep_file(list(laps), profiles, args.set)))
    done = run_sweep(
        load_sweep(spec_file), out, workers=args.workers, pictures="failed",
        stderr=sys.stderr, tty=sys.stderr.isatty(),
    )  # fmt: skip
    rows = [r for r in read_rows(out / "results.jsonl") if r["status"] == "ok"]
    extra = ", ".join(args.set) or "defaults"
    print(
        f"driving clean, {len(laps)} generated tracks, seeds {seeds.start}-{seeds.stop - 1} "
        f"(sizes by seed), 2 laps, fused localization, {extra}; {done.errors} errors"
    )
    print(
        f"  {'profile':8s} runs  clean    lap 2 / limit (min med max)  lap 2 / plan  "
        "DOO/km  not clean"
    )
    yardsticks: dict[int, tuple[float, float]] = {}  # seed: (limit, centreline) [s]
    for profile in profiles:
        mine = [r for r in rows if profile_of(r) == profile]
        if not mine:
            continue
        clean = [r for r in mine if r["clean"]]
        flying, to_plan = [], []
        km = 0.0
        for r in mine:
            result = json.loads((out / "runs" / r["run_id"] / "result.json").read_text())
            seed = int(r["axes"]["track.generate.seed"])
            yardsticks[seed] = (result["limit_lap_time_s"], result["centreline_lap_time_s"])
            times = result["lap_times_s"]
            if r["clean"] and len(times) >= 2:
                flying.append(times[1] / result["limit_lap_time_s"])
                to_plan.append(times[1] / laps[seed][1])
            km += laps[seed][0] * (r["laps_completed"] + 0.5 * (not r["finished"])) / 1000.0
        doo = sum(r["cones_down_or_out"] for r in mine)
        bad = ", ".join(
            f"{r['axes']['track.generate.seed']}:{r['end_reason']}/{r['cones_down_or_out']}"
            for r in mine
            if not r["clean"]
        )
        share = 100.0 * len(clean) / len(mine)
        plan_ratio = f"{float(np.median(to_plan)):.3f}" if to_plan else "n/a"
        print(
            f"  {profile:8s} {len(mine):4d} {share:5.1f} %  {spread(flying):27s}  "
            f"{plan_ratio:>12s}  {doo / km:6.2f}  {bad or '-'}"
        )
    if yardsticks:
        centre = [c / limit for limit, c in yardsticks.values()]
        plan = [laps[seed][1] / limit for seed, (limit, _) in yardsticks.items()]
        print(
            f"  where lap 2 / limit comes from, over {len(yardsticks)} tracks (min med max): "
            f"the centreline at the car's limits (QSS) / limit {spread(centre)}; the "
            f"autopilot's speed plan (the centreline at the planner's limits) / limit "
            f"{spread(plan)}"
        )


if __name__ == "__main__":
    main()
