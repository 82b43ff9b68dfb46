"""The sweep summary on synthetic rows, with worked numbers; the rows' file; the progress line."""

from __future__ import annotations

import io
import json
from pathlib import Path
from typing import Any

import pytest

from conesim.envs.cli import main
from conesim.envs.progress import SweepProgress
from conesim.envs.sweep_store import read_rows
from conesim.envs.sweep_summary import axis_tables, failed_markdown, summary_markdown

AXES = ["seed", "sensors.profile"]


def row(index: int, seed: int, sensors: str, **fields: Any) -> dict[str, Any]:
    base: dict[str, Any] = {
        "run_id": f"r{index}", "index": index, "axes": {"seed": str(seed),
        "sensors.profile": sensors}, "status": "ok", "clean": True, "finished": True,
        "end_reason": "laps_completed", "laps": 1, "laps_completed": 1, "cones_down_or_out": 0,
        "off_track_events": 0, "lap_time_ratio": 1.1, "localization_pos_rmse_m": 0.02,
    }  # fmt: skip
    base.update(fields)
    return base


ROWS = [
    row(0, 0, "rtk", lap_time_ratio=1.10, localization_pos_rmse_m=0.02),
    row(1, 0, "consumer", clean=False, finished=False, end_reason="off_track",
        laps_completed=0, off_track_events=1, cones_down_or_out=2, lap_time_ratio=None,
        localization_pos_rmse_m=0.5),
    row(2, 1, "rtk", lap_time_ratio=1.20, localization_pos_rmse_m=0.04),
    {"run_id": "r3", "index": 3, "axes": {"seed": "1", "sensors.profile": "consumer"},
     "status": "error", "clean": False, "error": {"type": "ValueError", "message": "boom"}},
]  # fmt: skip


def test_tables_worked_numbers() -> None:
    """Per value: runs, clean, errors, laps, cones, off-track totals, medians."""
    tables = axis_tables(ROWS, AXES)
    seed0, seed1 = tables["seed"]
    assert (seed0.value, seed0.runs, seed0.clean, seed0.errors) == ("0", 2, 1, 0)
    assert (seed0.laps_completed, seed0.laps, seed0.cones_down_or_out) == (1, 2, 2)
    assert seed0.off_track_events == 1
    assert seed0.lap_time_ratio == 1.10  # the only ratio
    assert seed0.localization_rmse_m == pytest.approx(0.26)  # median of 0.02 and 0.5
    assert (seed1.runs, seed1.clean, seed1.errors, seed1.laps) == (2, 1, 1, 1)
    rtk, consumer = tables["sensors.profile"]
    assert (rtk.value, rtk.clean_rate, rtk.lap_time_ratio) == ("rtk", 1.0, pytest.approx(1.15))
    assert rtk.localization_rmse_m == pytest.approx(0.03)
    assert (consumer.clean_rate, consumer.errors, consumer.lap_time_ratio) == (0.0, 1, None)
    text = summary_markdown(ROWS, AXES, total=5)
    assert "4 of 5 runs done: 2 clean (50%), 1 errors; median lap-time ratio 1.150" in text
    assert "| 0 | 2 | 1 | 50% | 0 | 1/2 | 2 | 1 | 1.100 | 0.260 |" in text
    assert "| consumer | 2 | 0 | 0% | 1 | 0/1 | 2 | 1 | n/a | 0.500 |" in text


def test_failed_gallery(tmp_path: Path) -> None:
    """failed.md: the runs not clean, with why; a picture where there is one."""
    (tmp_path / "runs" / "r1").mkdir(parents=True)
    (tmp_path / "runs" / "r1" / "run.png").write_bytes(b"png")
    text = failed_markdown(ROWS, tmp_path)
    assert "2 of 4 runs were not clean." in text
    assert "seed = 0, sensors.profile = consumer: **0/1 laps (off_track), 2 cones down or " in text
    assert "[![r1](runs/r1/run.png)](runs/r1/result.json)" in text
    assert "**error: ValueError: boom**" in text and "(runs/r3/error.txt)" in text
    assert "## r0" not in text


def test_rows_file_survives_a_cut_line(tmp_path: Path) -> None:
    """A last line cut short by a kill is dropped; a later row of a run replaces an earlier."""
    path = tmp_path / "results.jsonl"
    lines = [json.dumps(r) for r in ROWS[:3]] + [json.dumps({"run_id": "r0", "x": 1})]
    path.write_text("\n".join(lines) + '\n{"run_id": "r9", "cut')
    rows = read_rows(path)
    assert [r["run_id"] for r in rows] == ["r0", "r1", "r2"]
    assert rows[0] == {"run_id": "r0", "x": 1}


def test_summary_command_writes_the_summary_again(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`conesim sweep summary DIR` writes summary.md, summary.png, failed.md and prints it."""
    manifest = {"conesim_sweep_dir": 1, "fingerprint": "f", "axes": AXES, "runs": [{}] * 4}
    (tmp_path / "sweep.json").write_text(json.dumps(manifest))
    (tmp_path / "results.jsonl").write_text("".join(json.dumps(r) + "\n" for r in ROWS))
    assert main(["sweep", "summary", str(tmp_path)]) == 0
    assert "4 of 4 runs done: 2 clean (50%)" in capsys.readouterr().out
    assert (tmp_path / "summary.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "2 of 4 runs were not clean" in (tmp_path / "failed.md").read_text()
    assert "### sensors.profile" in (tmp_path / "summary.md").read_text()


def test_progress_lines_off_a_terminal() -> None:
    """Not a terminal: a line at each tenth of the runs; time left from the runs so far."""
    now = [0.0]
    stream = io.StringIO()
    progress = SweepProgress(stream, 20, skipped=4, clean=4, tty=False, clock=lambda: now[0])
    for k in range(16):
        now[0] += 2.0
        progress.finished(clean=k != 3, error=k == 5)
    lines = stream.getvalue().splitlines()
    # 4 done already: 20 %; then a line at 30 %, 40 %, ..., 100 %
    assert len(lines) == 8
    assert lines[0] == "conesim sweep: 6/20 runs, 6 clean, 0:28 left"  # 2 s a run, 14 left
    assert lines[-1] == "conesim sweep: 20/20 runs, 19 clean, 1 error, 0:00 left"


def test_progress_bar_on_a_terminal() -> None:
    """A terminal: the bar redrawn in place (carriage return) after every run."""
    stream = io.StringIO()
    progress = SweepProgress(stream, 4, tty=True, clock=lambda: 0.0)
    progress.finished(clean=True, error=False)
    progress.close()
    text = stream.getvalue()
    assert text.count("\r") == 2 and text.endswith("\n")
    assert "conesim sweep [#######.......................] 1/4 runs, 1 clean" in text
