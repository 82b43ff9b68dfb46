"""How reliably the autopilot completes its laps: many seeds per track. Prints figures.

The CI lap tests (``tests/envs/test_laps.py``) run 3 seeds per track; this
runs ``--seeds`` (default 20) per track with the same settings (rtk sensors,
fused localization by default, 2 laps) and prints, per track, how many runs were clean
(all laps completed, no cone down or out, no off-track event), the seeds of
the others and what happened, and the best-lap ratio against the
friction-limited lap (mean and worst over the clean runs).

Run: ``.venv/bin/python benchmarks/bench_laps.py [--seeds N] [--first S]
[--tracks a,b] [--jobs J] [--localization fused|raw|truth]`` (J worker
processes, default 2; about 3 s of wall time per run on one core).
"""

from __future__ import annotations

import argparse
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from conesim.envs.runner import run_scenario
from conesim.tracks import shipped_tracks


def one_run(job: tuple[str, int, str]) -> tuple[str, int, bool, str, int, int, float | None]:
    """(track, seed, clean, end reason, DOO cones, off-track events, lap ratio) of one run."""
    track, seed, localization = job
    r = run_scenario(track, laps=2, seed=seed, localization=localization)
    return (
        track, seed, r.clean, r.end_reason, r.cones_down_or_out, r.off_track_events,
        r.lap_time_ratio,
    )  # fmt: skip


def main() -> None:
    """Print the figures."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=20, help="seeds per track")
    parser.add_argument("--first", type=int, default=0, help="first seed")
    parser.add_argument("--tracks", default=",".join(shipped_tracks()))
    parser.add_argument("--jobs", type=int, default=2, help="worker processes")
    parser.add_argument("--localization", default="fused", choices=("fused", "raw", "truth"))
    args = parser.parse_args()
    tracks = [t.strip() for t in args.tracks.split(",") if t.strip()]
    seeds = range(args.first, args.first + args.seeds)
    jobs = [(t, s, args.localization) for t in tracks for s in seeds]
    with ProcessPoolExecutor(max(1, args.jobs)) as pool:
        results = list(pool.map(one_run, jobs))
    print(
        f"lap completion, rtk sensors, {args.localization} localization, 2 laps, seeds "
        f"{args.first}-{args.first + args.seeds - 1}"
    )
    print(f"  {'track':12s}  clean  best lap / limit (clean runs)  not clean")
    for track in tracks:
        rows = [r for r in results if r[0] == track]
        clean = [r for r in rows if r[2]]
        ratios = [r[6] for r in clean if r[6] is not None]
        ratio = f"mean {np.mean(ratios):.3f}x worst {max(ratios):.3f}x" if ratios else "n/a"
        others = ", ".join(
            f"seed {s}: {end}, {doo} DOO, {off} off"
            for _, s, ok, end, doo, off, _ in rows
            if not ok
        )
        print(f"  {track:12s}  {len(clean):2d}/{len(rows):<2d}  {ratio:29s}  {others or '-'}")


if __name__ == "__main__":
    main()
