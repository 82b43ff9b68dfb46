"""Check that a change of structure leaves the closed loop's runs as they were.

Runs a fixed list of headless runs through the command line (``conesim run``
in a fresh process each, so nothing is shared between runs) and writes each
run's ``result.json`` under ``OUT/<track>-<sensors>-<localization>-<seed>/``.
With ``--against REF`` it then compares every ``result.json`` with the one
of the same name under ``REF``, apart from the fields that depend on the
machine (wall time, real-time factor, setup time), and prints one line per
run: ``same`` or the fields that differ. A field the reference does not
have (one that ``result.json`` gained since, such as ``scenario``, or a key
inside one, such as ``scenario.cone_map``) is listed as new but is no
difference: every field the reference has must be the same, at every depth.

The list: every shipped track x ``rtk``/``consumer`` sensors x
``fused``/``raw``/``truth`` localization x seeds 0 and 1, one lap each.

Usage (before and after a change, from a checkout with ``make`` set up)::

    python scripts/check_runs_identical.py --out /tmp/before
    ...change...
    python scripts/check_runs_identical.py --out /tmp/after --against /tmp/before

Exit status: 0 when every run is the same (or no ``--against``), 1 when any
differs or is missing, 2 on bad arguments.
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import shutil
import subprocess
import sys
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

TRACKS = ("acceleration", "autocross", "skidpad", "trackdrive")
SENSORS = ("rtk", "consumer")
LOCALIZATION = ("fused", "raw", "truth")
SEEDS = (0, 1)
TIMING_FIELDS = ("wall_time_s", "real_time_factor", "setup_time_s")
"""The fields that depend on the machine, not on the run."""


def runs() -> Iterator[tuple[str, str, str, int]]:
    """The fixed run list: (track, sensors, localization, seed)."""
    yield from itertools.product(TRACKS, SENSORS, LOCALIZATION, SEEDS)


def run_name(track: str, sensors: str, localization: str, seed: int) -> str:
    """The run's directory name."""
    return f"{track}-{sensors}-{localization}-{seed}"


def conesim_command() -> list[str]:
    """The ``conesim`` console script beside this Python, else ``python -m``."""
    script = Path(sys.executable).with_name("conesim")
    return [str(script)] if script.exists() else [sys.executable, "-m", "conesim"]


def run_one(out: Path, track: str, sensors: str, localization: str, seed: int) -> str:
    """One run into ``out/<name>``; returns its name and exit status."""
    name = run_name(track, sensors, localization, seed)
    target = out / name
    if target.exists():
        shutil.rmtree(target)
    args = [
        *conesim_command(), "run", "--track", track, "--sensors", sensors,
        "--localization", localization, "--seed", str(seed), "--laps", "1",
        "--out", str(target),
    ]  # fmt: skip
    done = subprocess.run(args, capture_output=True, text=True, check=False)
    if done.returncode not in (0, 1):
        sys.stderr.write(done.stderr)
    return f"{name}: exit {done.returncode}"


def differences(a: dict[str, Any], b: dict[str, Any], prefix: str = "") -> list[str]:
    """The keys of the reference ``a`` whose values differ in ``b`` (timing fields
    left out), with both values, dotted at any depth. Keys new in ``b`` are not compared."""
    keys = sorted(set(a) - set(TIMING_FIELDS)) if not prefix else sorted(a)
    out: list[str] = []
    for k in keys:
        old, new = a.get(k), b.get(k)
        if isinstance(old, dict) and isinstance(new, dict):
            out += differences(old, new, f"{prefix}{k}.")
        elif old != new:
            out.append(f"{prefix}{k}: {old!r} -> {new!r}")
    return out


def new_keys(a: dict[str, Any], b: dict[str, Any], prefix: str = "") -> list[str]:
    """The keys of ``b`` that the reference ``a`` does not have, dotted at any depth."""
    out = [f"{prefix}{k}" for k in sorted(set(b) - set(a))]
    for k in sorted(set(a) & set(b)):
        if isinstance(a[k], dict) and isinstance(b[k], dict):
            out += new_keys(a[k], b[k], f"{prefix}{k}.")
    return out


def compare(out: Path, ref: Path) -> int:
    """Print one line per run; the number of runs that differ or are missing."""
    bad = 0
    added: set[str] = set()
    for track, sensors, localization, seed in runs():
        name = run_name(track, sensors, localization, seed)
        try:
            new = json.loads((out / name / "result.json").read_text())
            old = json.loads((ref / name / "result.json").read_text())
        except (OSError, ValueError) as exc:
            print(f"{name}: missing or unreadable ({exc})")
            bad += 1
            continue
        diff = differences(old, new)
        added.update(new_keys(old, new))
        print(f"{name}: same" if not diff else f"{name}: DIFFERS")
        for line in diff:
            print(f"    {line}")
        bad += bool(diff)
    if added:
        print(f"new fields, not in the reference (not compared): {', '.join(sorted(added))}")
    return bad


def main() -> int:
    """Run the list, then compare if asked."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True, help="directory for this checkout's runs")
    parser.add_argument("--against", help="directory of the reference runs to compare with")
    parser.add_argument(
        "--workers", type=int, default=os.cpu_count() or 1, help="runs at once (default: cores)"
    )
    parser.add_argument(
        "--compare-only", action="store_true", help="compare existing runs, run nothing"
    )
    args = parser.parse_args()
    out = Path(args.out)
    if not args.compare_only:
        out.mkdir(parents=True, exist_ok=True)
        with ThreadPoolExecutor(max(1, args.workers)) as pool:
            jobs = [pool.submit(run_one, out, *r) for r in runs()]
            for job in jobs:
                print(job.result(), flush=True)
    if args.against is None:
        return 0
    bad = compare(out, Path(args.against))
    total = len(list(runs()))
    print(f"{total - bad} of {total} runs the same")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
