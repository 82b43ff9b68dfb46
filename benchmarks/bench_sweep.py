"""Sweep throughput: the same sweep serial, on a 2-process pool, and on a 2-CPU local Ray.

The sweep: 24 runs of the kind a driving sweep is made of (autocross and
trackdrive x seeds 0-11, two laps, fused localization, rtk sensors; about a
second each here), with no pictures: drawing ``run.png`` is the same work
on every executor. Each
repeat runs the three executors one after the other (interleaved: this
machine's speed drifts about 2x), each into a new directory through
``envs.sweep.run_sweep``; the figures are the medians over the repeats.

Printed per executor:

* end to end [runs/s]: the runs over the call's wall time. The pool's
  includes starting its workers (spawn, import, loading the kernels); the
  serial sweep runs in this process, already warm; Ray's includes starting
  its actors (one per CPU, warmed as the pool's workers are) but not the
  local Ray itself (``ray_session``, as ``conesim sweep --ray`` starts it;
  printed apart), as with ``--ray ADDRESS``.
* steady [runs/s]: after the first run of each worker (the start-up), the
  runs finished over the time they took;
* 1st row [s]: from the call to the first run written (the pool's worker
  start-up shows here);
* a run [s]: the median of the runs' own time (setup and loop) in their
  worker: above the serial figure, the workers did not have a core each
  (other work on the machine, or two workers on one physical core);
* in flight: steady x a run, the runs kept going at once. An executor
  that keeps its workers busy shows its worker count; its speed-up over
  serial is then the in-flight ratio times serial's run time over its own.

Targets (issue 14): 2 workers at least 1.8x one; Ray within 15 % of the
pool. A reference measured in the same run, before and after: bare pymunk
steps per second (``write_results.pymunk_reference``).

Run: ``.venv/bin/python benchmarks/bench_sweep.py [--repeats N]`` (about
5 minutes with 3 repeats on 2 idle cores; ``--seeds`` sets the length).
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time
from pathlib import Path
from typing import Any

from write_results import pymunk_reference

from conesim.envs.runner import run_scenario
from conesim.envs.sweep import LOCAL_RAY, run_sweep
from conesim.envs.sweep_file import load_sweep
from conesim.envs.sweep_workers import ray_session

SWEEP = """\
conesim_sweep: 1
base: {laps: 2, localization: fused, sensors: rtk}
axes:
  track: [autocross, trackdrive]
  seed: {range: [0, SEEDS]}
"""
WORKERS = 2


def timed_sweep(path: Path, out: Path, **how: Any) -> dict[str, float]:
    """One sweep's figures: end-to-end and steady runs/s, the time to its first row [s],
    and the median of its runs' own time (setup + loop, in the worker) [s]."""
    stamps: list[float] = []
    own: list[float] = []

    def on_row(row: dict[str, Any]) -> None:
        stamps.append(time.perf_counter())
        own.append(row["wall_time_s"] + row["setup_time_s"])

    t0 = time.perf_counter()
    report = run_sweep(load_sweep(path), out, pictures="none", on_row=on_row, **how)
    wall = time.perf_counter() - t0
    first = 1 if how.get("workers", 1) == 1 else WORKERS
    return {
        "e2e": report.ran / wall,
        "steady": (len(stamps) - first) / (stamps[-1] - stamps[first - 1]),
        "first": stamps[0] - t0,
        "run": statistics.median(own),
    }


def main() -> None:
    """Print the figures."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--seeds", type=int, default=12, help="seeds per track (runs: 2 x this)")
    args = parser.parse_args()

    before, load0 = pymunk_reference(), os.getloadavg()[0]
    run_scenario("skidpad", localization="fused")  # this process warm, as the CLI's would be
    figures: dict[str, list[dict[str, float]]] = {"serial": [], "pool": [], "ray": []}
    ray_start: list[float] = []
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "sweep.yaml"
        path.write_text(SWEEP.replace("SEEDS", str(args.seeds)))
        for repeat in range(args.repeats):
            out = Path(tmp) / str(repeat)
            figures["serial"].append(timed_sweep(path, out / "serial", workers=1))
            figures["pool"].append(timed_sweep(path, out / "pool", workers=WORKERS))
            t0 = time.perf_counter()
            with ray_session(WORKERS, None):  # as the CLI starts it
                ray_start.append(time.perf_counter() - t0)
                figures["ray"].append(
                    timed_sweep(path, out / "ray", workers=WORKERS, ray=LOCAL_RAY)
                )
    after, load1 = pymunk_reference(), os.getloadavg()[0]
    med = {k: {f: statistics.median(r[f] for r in v) for f in v[0]} for k, v in figures.items()}
    print(
        f"sweep of {2 * args.seeds} runs (autocross, trackdrive x {args.seeds} seeds, 2 laps, "
        "fused, no pictures), "
        f"median of {args.repeats} interleaved repeats"
    )
    print(f"  reference, bare pymunk: {before:,.0f} steps/s before, {after:,.0f} after")
    print(f"  load average (1 min): {load0:.1f} before, {load1:.1f} after ({os.cpu_count()} cores)")
    print(f"  {'executor':22s} {'end to end':>10s} {'steady':>8s} [runs/s] {'1st row':>8s} "
          f"{'a run':>7s} [s]  in flight")  # fmt: skip
    names = {"serial": "serial (--workers 1)", "pool": f"pool, {WORKERS} workers",
             "ray": f"local Ray, {WORKERS} CPUs"}  # fmt: skip
    for key, label in names.items():
        m = med[key]
        print(
            f"  {label:22s} {m['e2e']:10.2f} {m['steady']:8.2f}          {m['first']:8.2f} "
            f"{m['run']:7.2f}      {m['steady'] * m['run']:5.2f}"
        )
    print(f"  local Ray start (ray.init, not in the figures): {statistics.median(ray_start):.1f} s")
    for a, b, target in (("pool", "serial", ">= 1.8x"), ("ray", "pool", ">= 0.85x")):
        e2e, steady = med[a]["e2e"] / med[b]["e2e"], med[a]["steady"] / med[b]["steady"]
        paired = statistics.median(
            x["e2e"] / y["e2e"] for x, y in zip(figures[a], figures[b], strict=True)
        )
        print(
            f"  {a} / {b}: {e2e:.2f}x end to end, {steady:.2f}x steady; "
            f"{paired:.2f}x end to end within a repeat, median (target {target})"
        )
    print(
        "  ('a run': a run's own setup + loop time in its worker, above serial's where the "
        "workers shared cores;\n   'in flight': steady x a run, the runs kept going at once: "
        "the executor's own overhead shows as less than its workers)"
    )


if __name__ == "__main__":
    main()
