"""Sweeps run: serial, 2-worker pool and Ray give the same results bit for bit; nothing is lost
when a run raises, a worker dies, or the sweep is killed and resumed."""

from __future__ import annotations

import json
import multiprocessing
import os
import signal
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path
from typing import Any

import pytest

from conesim.envs.runner import TIMING_FIELDS
from conesim.envs.sweep import LOCAL_RAY, run_sweep
from conesim.envs.sweep_file import load_sweep
from conesim.envs.sweep_store import RESULTS, read_rows
from tests.envs.sweep_helpers import copy_track

CONESIM = [sys.executable, "-m", "conesim.envs.cli"]

FUSED = """\
conesim_sweep: 1
base: {laps: 1, localization: fused}
axes:
  track: [acceleration, skidpad]
  seed: [0, 1]
"""
"""4 short runs with the EKF (its compiled kernels in play)."""

QUICK = """\
conesim_sweep: 1
base: {track: skidpad, laps: 1, localization: truth}
axes:
  seed: {range: [0, 4]}
"""
"""4 quick runs (about 0.4 s each, and a picture)."""
KILLED_RUNS = 24
LONGER = QUICK.replace("range: [0, 4]", f"range: [0, {KILLED_RUNS}]")
"""24 of them: a sweep still busy when the test's signal lands, on any machine
(16 finished before it on a busy 2-core machine, the test starved of time)."""


def comparable(out: Path) -> dict[str, Any]:
    """Per run id, its row and result.json without the timing fields (and no row twice)."""
    lines = (out / RESULTS).read_text().splitlines()
    rows = [json.loads(line) for line in lines]
    assert max(Counter(r["run_id"] for r in rows).values()) == 1, "a row written twice"
    same: dict[str, Any] = {}
    for row in rows:
        result = json.loads((out / "runs" / row["run_id"] / "result.json").read_text())
        for fields in (row, result):
            for name in TIMING_FIELDS:
                fields.pop(name, None)
        same[row["run_id"]] = (row, result)
    return same


def sweep_file(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "sweep.yaml"
    path.write_text(text)
    return path


@pytest.fixture(scope="module")
def serial_fused(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """The fused sweep run in this process, one run after the other."""
    tmp = tmp_path_factory.mktemp("serial")
    report = run_sweep(load_sweep(sweep_file(tmp, FUSED)), tmp / "out", workers=1, pictures="none")
    assert (report.total, report.ran, report.errors) == (4, 4, 0)
    return comparable(tmp / "out")


@pytest.fixture(scope="module")
def serial_quick(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """The quick sweep run in this process."""
    tmp = tmp_path_factory.mktemp("quick")
    run_sweep(load_sweep(sweep_file(tmp, QUICK)), tmp / "out", workers=1, pictures="none")
    return comparable(tmp / "out")


def test_two_workers_equal_serial_bit_for_bit(tmp_path: Path, serial_fused: dict[str, Any]) -> None:
    """A 2-process pool gives every run's row and result.json exactly as the serial sweep."""
    run_sweep(load_sweep(sweep_file(tmp_path, FUSED)), tmp_path / "out", workers=2, pictures="none")
    assert comparable(tmp_path / "out") == serial_fused


def test_ray_equals_serial_bit_for_bit(tmp_path: Path, serial_fused: dict[str, Any]) -> None:
    """A real local Ray (2 CPUs) gives every run exactly as the serial sweep."""
    pytest.importorskip("ray")
    run_sweep(
        load_sweep(sweep_file(tmp_path, FUSED)), tmp_path / "out", workers=2, ray=LOCAL_RAY,
        pictures="none",
    )  # fmt: skip
    assert comparable(tmp_path / "out") == serial_fused


def test_a_run_that_raises_is_recorded_and_the_sweep_goes_on(tmp_path: Path) -> None:
    """A track file broken after the checks (between runs): its run is an error row with its
    traceback, the runs after it still run, and the summary counts it."""
    mine = copy_track("skidpad", tmp_path / "mine.yaml")
    path = sweep_file(
        tmp_path,
        "base: {laps: 1, localization: truth}\npoints:\n- {track: skidpad}\n"
        "- {track: mine.yaml}\n- {track: skidpad, seed: 1}\n",
    )

    def break_track(row: dict[str, Any]) -> None:
        if row["index"] == 0:
            mine.write_text("cones: [oops\n")

    report = run_sweep(load_sweep(path), tmp_path / "out", workers=1, on_row=break_track)
    assert (report.total, report.ran, report.clean, report.errors) == (3, 3, 2, 1)
    rows = [json.loads(line) for line in (tmp_path / "out" / RESULTS).read_text().splitlines()]
    assert [r["status"] for r in rows] == ["ok", "error", "ok"]
    assert rows[1]["error"]["type"] == "TrackFormatError"
    assert "mine.yaml" in rows[1]["error"]["message"]
    traceback = (tmp_path / "out" / "runs" / rows[1]["run_id"] / "error.txt").read_text()
    assert traceback.startswith("Traceback") and "TrackFormatError" in traceback
    assert "3 of 3 runs done: 2 clean (67%), 1 errors" in report.summary
    for row, files in zip(rows, [["result.json", "run.png"], ["error.txt"]] * 2, strict=False):
        assert (
            sorted(p.name for p in (tmp_path / "out" / "runs" / row["run_id"]).iterdir()) == files
        )
    failed = (tmp_path / "out" / "failed.md").read_text()
    assert "1 of 3 runs were not clean" in failed and "error: TrackFormatError" in failed


def test_a_killed_worker_loses_nothing(tmp_path: Path, serial_quick: dict[str, Any]) -> None:
    """A pool worker killed mid-sweep: the runs it may have held run again, every row once,
    the same as the serial sweep."""
    path = sweep_file(tmp_path, QUICK)
    killed: list[int] = []

    def kill_a_worker(row: dict[str, Any]) -> None:
        if not killed:
            worker = multiprocessing.active_children()[0]
            killed.append(worker.pid or 0)
            os.kill(worker.pid or 0, signal.SIGKILL)

    report = run_sweep(
        load_sweep(path), tmp_path / "pool", workers=2, pictures="none", on_row=kill_a_worker
    )
    assert killed
    assert (report.ran, report.errors) == (4, 0)
    assert comparable(tmp_path / "pool") == serial_quick


def ray_actor_pids() -> list[int]:
    """The pids of this process's local Ray's run actors (``ray::RunActor``: the raylet this
    process started is their parent, so another test's Ray is left alone)."""

    def parent(pid: int) -> int:
        try:
            return int(Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[1])
        except (OSError, ValueError, IndexError):
            return 0

    pids = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            command = (entry / "cmdline").read_bytes()
        except OSError:
            continue
        pid = int(entry.name)
        if command.startswith(b"ray::RunActor") and parent(parent(pid)) == os.getpid():
            pids.append(pid)
    return pids


@pytest.mark.skipif(not Path("/proc").is_dir(), reason="finds the actors' processes in /proc")
def test_a_killed_ray_actor_loses_nothing(tmp_path: Path, serial_quick: dict[str, Any]) -> None:
    """A real local Ray's run actors killed mid-sweep: the runs they held run again on new
    actors, every row once, the same as the serial sweep."""
    pytest.importorskip("ray")
    killed: list[int] = []

    def kill_the_actors(row: dict[str, Any]) -> None:
        if not killed:
            killed.extend(ray_actor_pids())
            for pid in killed:
                os.kill(pid, signal.SIGKILL)

    report = run_sweep(
        load_sweep(sweep_file(tmp_path, QUICK)), tmp_path / "ray", workers=2, ray=LOCAL_RAY,
        pictures="none", on_row=kill_the_actors,
    )  # fmt: skip
    assert len(killed) == 2
    assert (report.ran, report.errors) == (4, 0)
    assert comparable(tmp_path / "ray") == serial_quick


def wait_for_rows(out: Path, count: int, proc: subprocess.Popen[bytes]) -> None:
    """Until ``out`` has ``count`` rows (a generous bound that only stops a hang)."""
    deadline = time.monotonic() + 300.0
    while time.monotonic() < deadline and proc.poll() is None:
        results = out / RESULTS
        if results.exists() and len(results.read_text().splitlines()) >= count:
            return
        time.sleep(0.05)
    raise AssertionError(f"the sweep ended or hung before {count} rows")


@pytest.mark.parametrize(("sig", "workers"), [(signal.SIGKILL, "1"), (signal.SIGINT, "2")])
def test_killed_sweep_resumes(tmp_path: Path, sig: signal.Signals, workers: str) -> None:
    """`conesim sweep` killed (SIGKILL to its process group, or Ctrl-C) after some rows, then
    run again: it skips those, runs the rest, no row twice, the rows of an uninterrupted sweep."""
    path = sweep_file(tmp_path, LONGER)
    out = tmp_path / "out"
    command = [*CONESIM, "sweep", str(path), "--out", str(out), "--workers", workers]
    command += ["--pictures", "none"]
    # Ctrl-C as in a terminal: the sweep starts with SIGINT's default action
    # whatever this test process holds (a child inherits an ignored signal, and
    # in the whole suite the sweep ran on after SIGINT, as if it was ignored).
    held = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        proc = subprocess.Popen(
            command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True
        )
    finally:
        signal.signal(signal.SIGINT, held)
    try:
        wait_for_rows(out, 1, proc)
        if sig == signal.SIGKILL:
            os.killpg(proc.pid, sig)
        else:
            proc.send_signal(sig)
        _, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    if sig == signal.SIGINT:
        assert proc.returncode == 130, err.decode()[-500:]
        assert b"interrupted; the runs finished are in" in err
    done = len(read_rows(out / RESULTS))  # a row cut short by the signal is not one
    assert 1 <= done < KILLED_RUNS
    again = subprocess.run(command, capture_output=True, text=True, check=False)
    assert again.returncode == 0, again.stderr
    n = KILLED_RUNS
    assert f"{n} runs: {done} done before, {n - done} run now; {n} clean" in again.stdout
    run_sweep(load_sweep(path), tmp_path / "serial", workers=1, pictures="none")
    assert comparable(out) == comparable(tmp_path / "serial")
