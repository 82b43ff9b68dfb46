"""Tests for the conesim command line: tracks, track show/check, run, bad input."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from envs.cli import main
from tracks import load_track


def run_cli(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    """Exit code, stdout and stderr of one invocation."""
    code = main(args)
    out = capsys.readouterr()
    return code, out.out, out.err


def trackdrive_cones() -> dict[str, np.ndarray]:
    """The default track's cones by kind, to write in other formats."""
    track = load_track("trackdrive")
    kinds = np.array([str(k) for k in track.kinds])
    return {k: track.cones[kinds == k] for k in ("blue", "yellow", "orange", "big_orange")}


def write_fssim(path: Path) -> None:
    """An fssim YAML of the default track's cones."""
    cones = trackdrive_cones()
    lines = []
    for key, kind in (
        ("cones_left", "blue"),
        ("cones_right", "yellow"),
        ("cones_orange", "orange"),
        ("cones_orange_big", "big_orange"),
    ):
        lines.append(f"{key}:")
        lines += [f"- [{x:.4f}, {y:.4f}]" for x, y in cones[kind]]
        if not len(cones[kind]):
            lines[-1] = f"{key}: []"
    lines.append("starting_pose_front_wing: [-3.0, 0.0, 0.0]")
    path.write_text("\n".join(lines) + "\n")


def write_seven_columns(path: Path, header: bool) -> None:
    """An EUFS (with header and car_start) or FSDS (no header) CSV of the default track."""
    rows = ["tag,x,y,direction,x_variance,y_variance,xy_covariance"] if header else []
    for kind, pts in trackdrive_cones().items():
        rows += [f"{kind},{x:.4f},{y:.4f},0,0.01,0.01,0" for x, y in pts]
    if header:
        rows.append("car_start,-4.0,0.0,0.0,0,0,0")
    path.write_text("\n".join(rows) + "\n")


def test_tracks_lists_every_shipped_track(capsys: pytest.CaptureFixture[str]) -> None:
    """`conesim tracks` prints one row per shipped track, the default marked."""
    code, out, _ = run_cli(["tracks"], capsys)
    assert code == 0
    for name in ("trackdrive", "autocross", "acceleration", "skidpad"):
        assert name in out
    assert "(default)" in out


@pytest.mark.parametrize("fmt", ["fssim", "eufs", "fsds"])
def test_track_check_json_counts_external_files(
    fmt: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Files in the three foreign formats, with a neutral extension, are counted correctly."""
    path = tmp_path / f"{fmt}_track.txt"
    if fmt == "fssim":
        write_fssim(path)
    else:
        write_seven_columns(path, header=fmt == "eufs")
    code, out, err = run_cli(["track", "check", str(path), "--json"], capsys)
    assert code == 0, err
    report = json.loads(out)
    cones = trackdrive_cones()
    assert report["cones"] == {
        "blue": len(cones["blue"]),
        "yellow": len(cones["yellow"]),
        "orange": 0,
        "big_orange": len(cones["big_orange"]),
        "unknown": 0,
    }
    assert report["errors"] == []
    assert report["length_m"] == pytest.approx(load_track("trackdrive").length_m, rel=0.02)
    assert 3.0 <= report["width_min_m"] <= report["width_max_m"] <= 6.0


def test_track_show_writes_png(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """`conesim track show` writes a PNG and reports the red (high covariance) points."""
    out_file = tmp_path / "pics" / "autocross.png"
    code, out, _ = run_cli(["track", "show", "autocross", "--out", str(out_file)], capsys)
    assert code == 0
    assert out_file.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "above cov 0.0025" in out
    assert [p.name for p in out_file.parent.iterdir()] == ["autocross.png"]


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"", "empty"),
        (b"\x00\x01\x02\x03binary", "binary"),
        (b"blue,1.0,abc,0,0,0,0\nyellow,1,2,0,0,0,0\n", "abc"),
        (b"cones_left: 5\n", "cones_left"),
        (b"blue,nan,1.0,0,0,0,0\nyellow,1,2,0,0,0,0\n", "nan"),
    ],
)
def test_bad_track_files_exit_2_with_one_line(
    content: bytes, message: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Corrupted files: exit 2, one line naming the file and the problem, no traceback."""
    path = tmp_path / "broken.csv"
    path.write_bytes(content)
    for args in (["track", "check", str(path)], ["run", "--track", str(path)]):
        code, out, err = run_cli(args, capsys)
        assert code == 2
        assert out == ""
        lines = err.strip().splitlines()
        assert len(lines) == 1, err
        assert "broken.csv" in lines[0] and message.lower() in lines[0].lower()
        assert "Traceback" not in err


def test_unknown_track_name_lists_shipped(capsys: pytest.CaptureFixture[str]) -> None:
    """An unknown name exits 2 and lists the shipped tracks."""
    code, _, err = run_cli(["track", "check", "monza"], capsys)
    assert code == 2 and "trackdrive" in err


def test_run_json_on_acceleration(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """`conesim run --json` drives the acceleration lane and writes result.json and run.png."""
    out_dir = tmp_path / "run"
    code, out, _ = run_cli(
        ["run", "--track", "acceleration", "--sensors", "ideal", "--out", str(out_dir), "--json"],
        capsys,
    )
    result = json.loads(out)
    assert code == 0 and result["finished"]
    assert json.loads((out_dir / "result.json").read_text()) == result
    assert (out_dir / "run.png").read_bytes()[:4] == b"\x89PNG"
    required = {
        "track", "seed", "sensors", "localization", "finished", "end_reason",
        "laps_completed", "lap_times_s", "cones_hit", "cones_down_or_out",
        "off_track_events", "sim_time_s", "wall_time_s", "real_time_factor",
        "localization_pos_rmse_m", "localization_yaw_rmse_deg", "midline_rmse_m",
        "planner_fallbacks", "limit_lap_time_s",
    }  # fmt: skip
    assert required <= set(result)
    assert result["laps_completed"] == 1 and result["cones_down_or_out"] == 0
    # A car at full throttle ties the limit; the QSS is exact to 1e-4 (its grid).
    assert result["lap_times_s"][0] >= result["limit_lap_time_s"] * (1 - 1e-4)
    assert math.isfinite(result["real_time_factor"])


def test_run_bad_arguments_exit_2(capsys: pytest.CaptureFixture[str]) -> None:
    """--laps 0 is bad input."""
    code, _, err = run_cli(["run", "--laps", "0"], capsys)
    assert code == 2 and "--laps" in err


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--seed", "-1"], "--seed"),
        (["--laps", "1000"], "--laps"),
        (["--out", "FILE/sub"], "--out"),
    ],
)
def test_run_input_errors_before_any_simulation(
    extra: list[str], message: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Bad seed, laps or output directory: exit 2, one line naming the option, nothing written."""
    (tmp_path / "FILE").write_text("a file, not a directory")
    args = [a.replace("FILE", str(tmp_path / "FILE")) for a in extra]
    code, out, err = run_cli(["run", *args], capsys)
    assert code == 2 and out == ""
    assert len(err.strip().splitlines()) == 1 and message in err


def test_run_render_without_pygame(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    """--render without the render extra names the extra and exits 2."""
    import sys

    monkeypatch.setitem(sys.modules, "pygame", None)
    code, _, err = run_cli(["run", "--render", "--out", str(tmp_path)], capsys)
    assert code == 2 and "conesim[render]" in err


def test_track_check_reports_a_broken_global_path(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A track whose lat,lon,cov CSV is malformed is bad input for `track check` too."""
    track_file = tmp_path / "t.yaml"
    (tmp_path / "t_path.csv").write_text("37.5,abc,0.1\n37.6,127.0,0.1\n")
    text = (Path(load_track("trackdrive").source or "")).read_text()
    track_file.write_text(
        "\n".join(
            "global_path: t_path.csv" if line.startswith("global_path:") else line
            for line in text.splitlines()
        )
    )
    code, _, err = run_cli(["track", "check", str(track_file)], capsys)
    assert code == 2 and "t_path.csv:1" in err and "abc" in err
