"""Run every benchmark and write their figures to ``benchmarks/RESULTS.md`` (``make bench``).

Each ``benchmarks/bench_*.py`` runs in a process of its own; what it prints
is shown as it comes and kept. ``RESULTS.md`` gets, per script, its output
in a code block, under a header that says when, on which commit and on what
machine it was measured, with a reference measured in the same run before
and after the scripts: bare pymunk steps per second (one dynamic box in an
empty space), so that a figure can be read against the machine's speed at
the time (this machine's speed drifts about 2x between quiet and busy
moments). The file is replaced only when every script has run; a script
that fails stops the run with its exit status and leaves the old file.

Usage: ``python benchmarks/write_results.py [--only bench_env,bench_laps]``
(``--only`` runs those and writes ``RESULTS.md`` with just them).
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import subprocess
import sys
from pathlib import Path

import pymunk

from timing import pymunk_reference

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "RESULTS.md"


def machine() -> str:
    """The machine in one line: CPU, cores, Python, pymunk."""
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return (
        f"{cpu}, {os.cpu_count()} cores; Python {platform.python_version()}, "
        f"pymunk {pymunk.version}"
    )


def commit() -> str:
    """The checkout's commit (with ``+changes`` when the tree differs from it)."""

    def git(*args: str) -> str:
        done = subprocess.run(["git", *args], cwd=HERE, capture_output=True, text=True, check=False)
        return done.stdout.strip() if done.returncode == 0 else ""

    head = git("rev-parse", "--short", "HEAD") or "unknown"
    return head + ("+changes" if git("status", "--porcelain", "--untracked-files=no") else "")


def run(script: Path) -> str:
    """Run one benchmark; its output (shown as it comes)."""
    print(f"== {script.name}", flush=True)
    lines: list[str] = []
    with subprocess.Popen(
        [sys.executable, str(script)], cwd=HERE, stdout=subprocess.PIPE, text=True
    ) as proc:
        assert proc.stdout is not None
        for line in proc.stdout:
            sys.stdout.write(line)
            lines.append(line)
    if proc.returncode != 0:
        raise SystemExit(f"{script.name} failed with exit status {proc.returncode}")
    return "".join(lines)


def main() -> int:
    """Run the scripts, then write RESULTS.md."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", help="comma-separated script names (without .py)")
    args = parser.parse_args()
    scripts = sorted(HERE.glob("bench_*.py"))
    if args.only:
        wanted = {name.strip() for name in args.only.split(",")}
        unknown = wanted - {s.stem for s in scripts}
        if unknown:
            print(f"write_results: unknown scripts {sorted(unknown)}", file=sys.stderr)
            return 2
        scripts = [s for s in scripts if s.stem in wanted]
    started = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC")
    before = pymunk_reference()
    outputs = {script.name: run(script) for script in scripts}
    after = pymunk_reference()
    parts = [
        "# Benchmark results\n",
        "Written by `make bench` (`benchmarks/write_results.py`); do not edit by hand.\n",
        f"- measured: {started}, commit {commit()}",
        f"- machine: {machine()}",
        f"- reference, bare pymunk (one box, no contacts): {before:,.0f} steps/s before the "
        f"scripts, {after:,.0f} after\n",
    ]
    for name, text in outputs.items():
        parts += [f"## {name}\n", "```", text.rstrip("\n"), "```\n"]
    tmp = RESULTS.with_suffix(".md.tmp")
    tmp.write_text("\n".join(parts), encoding="utf-8")
    os.replace(tmp, RESULTS)
    print(f"wrote {RESULTS.relative_to(HERE.parent)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
