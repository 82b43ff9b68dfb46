"""Tests for the conesim command line: tracks, track show/check, run, bad input."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path
from typing import cast

import numpy as np
import pytest
from matplotlib.figure import Figure

from conesim.core.geodesy import GeodesyError
from conesim.envs import cli, runner, scenario
from conesim.envs.cli import build_parser, format_result, main
from conesim.envs.loop import ClosedLoop
from conesim.envs.runner import RunResult
from conesim.tracks import Track, load_track
from conesim.tracks.global_path import GlobalPath


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
        "setup_time_s", "localization_pos_rmse_m", "localization_yaw_rmse_deg", "midline_rmse_m",
        "planner_fallbacks", "limit_lap_time_s", "centreline_lap_time_s",
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


def test_run_render_without_a_display(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    """--render on Linux with no display would draw into nothing, slowly:
    exit 2 before simulating, nothing written."""
    pytest.importorskip("pygame")
    monkeypatch.setattr("sys.platform", "linux")
    for name in ("DISPLAY", "WAYLAND_DISPLAY", "SDL_VIDEODRIVER"):
        monkeypatch.delenv(name, raising=False)
    out = tmp_path / "out"
    code, _, err = run_cli(["run", "--render", "--out", str(out)], capsys)
    assert (
        code == 2
        and "--render: no display (DISPLAY or WAYLAND_DISPLAY is not set)" in err
        and not out.exists()
    )


def trackdrive_with_global_path(tmp_path: Path, csv: str) -> Path:
    """trackdrive's conesim YAML in ``tmp_path`` with its global path replaced by ``csv``."""
    track_file = tmp_path / "t.yaml"
    (tmp_path / "t_path.csv").write_text(csv)
    text = (Path(load_track("trackdrive").source or "")).read_text()
    track_file.write_text(
        "\n".join(
            "global_path: t_path.csv" if line.startswith("global_path:") else line
            for line in text.splitlines()
        )
    )
    return track_file


def test_track_check_reports_a_broken_global_path(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A track whose lat,lon,cov CSV is malformed is bad input for `track check` too."""
    track_file = trackdrive_with_global_path(tmp_path, "37.5,abc,0.1\n37.6,127.0,0.1\n")
    code, _, err = run_cli(["track", "check", str(track_file)], capsys)
    assert code == 2 and "t_path.csv:1" in err and "abc" in err
    code, out, err = run_cli(["track", "check", str(track_file), "--json"], capsys)
    report = json.loads(out)
    assert code == 2 and report["input_error"] is True and report["track"] == str(track_file)
    assert len(report["errors"]) == 1 and "t_path.csv:1" in report["errors"][0]
    assert err.strip() == f"conesim: error: {report['errors'][0]}"


def test_track_check_json_of_a_missing_track_is_json(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`track check --json` of a track that is not there: exit 2, the error on
    stderr and as JSON on stdout; without --json, stdout stays empty."""
    missing = str(tmp_path / "nope.yaml")
    code, out, err = run_cli(["track", "check", missing, "--json"], capsys)
    assert code == 2 and json.loads(out)["errors"] == [err.strip().removeprefix("conesim: error: ")]
    code, out, _ = run_cli(["track", "check", missing], capsys)
    assert code == 2 and out == ""


def test_a_global_path_of_another_place_is_an_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """trackdrive with a global path 10,000 km away: `track check` reports
    it (exit 1), `run` refuses it (exit 2) and writes nothing."""
    track_file = trackdrive_with_global_path(tmp_path, "-89.0,179.9,0.0001\n-89.0,179.91,0.0001\n")
    code, out, _ = run_cli(["track", "check", str(track_file)], capsys)
    assert code == 1 and "error: global path t_path.csv: 2 of 2 points lie" in out
    out_dir = tmp_path / "out"
    code, out, err = run_cli(["run", "--track", str(track_file), "--out", str(out_dir)], capsys)
    assert code == 2 and "does not follow the track" in err and not out_dir.exists()


def assert_bad_input(
    code: int, out: str, err: str, *must_contain: str, lines: int | None = 1
) -> list[str]:
    """Exit 2, nothing on stdout, no traceback, `lines` stderr lines (None: any) with the texts."""
    assert code == 2, err
    assert out == ""
    assert "Traceback" not in err
    got = err.strip().splitlines()
    if lines is not None:
        assert len(got) == lines, err
    assert all(line.startswith("conesim: error: ") for line in got), err
    for text in must_contain:
        assert text in err, err
    return got


def write_reversed_fssim(path: Path) -> None:
    """The default track's fssim file with left and right swapped (blue on the right)."""
    write_fssim(path)
    text = path.read_text().replace("cones_left", "SWAP").replace("cones_right", "cones_left")
    path.write_text(text.replace("SWAP", "cones_right"))


def write_far_start_fssim(path: Path) -> None:
    """The default track's fssim file with its start pose far outside the track."""
    write_fssim(path)
    path.write_text(path.read_text().replace("[-3.0, 0.0, 0.0]", "[500.0, 500.0, 0.0]"))


@pytest.mark.parametrize(
    ("writer", "message"),
    [
        (write_reversed_fssim, "blue cones lie on the right"),
        (write_far_start_fssim, "is outside the track"),
    ],
)
def test_run_refuses_a_track_that_check_reports_errors_in(
    writer: object, message: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`run` exits 2 on the errors `track check` finds, one line each naming the file."""
    path = tmp_path / "bad.yaml"
    writer(path)  # type: ignore[operator]
    code, out, _ = run_cli(["track", "check", str(path), "--json"], capsys)
    errors = json.loads(out)["errors"]
    assert code == 1 and errors
    out_dir = tmp_path / "run"
    code, out, err = run_cli(["run", "--track", str(path), "--out", str(out_dir)], capsys)
    got = assert_bad_input(code, out, err, message, lines=len(errors))
    assert all(line.startswith(f"conesim: error: {path}: ") for line in got)
    assert not out_dir.exists()


def test_verbose_before_or_after_the_subcommand() -> None:
    """`-v` works in both places and defaults to off."""
    parser = build_parser()
    assert parser.parse_args(["-v", "run"]).verbose
    assert parser.parse_args(["run", "-v"]).verbose
    assert parser.parse_args(["track", "check", "x", "--verbose"]).verbose
    assert not parser.parse_args(["run"]).verbose
    assert not parser.parse_args(["tracks"]).verbose


def test_track_show_unwritable_out_names_the_users_path(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A file as parent, a directory as target, a refused write: one line naming --out."""
    (tmp_path / "afile").write_text("not a directory")
    (tmp_path / "adir.png").mkdir()
    for out_file, message in (
        (tmp_path / "afile" / "x.png", "afile is not a directory"),
        (tmp_path / "afile" / "sub" / "x.png", "afile is not a directory"),
        (tmp_path / "adir.png", "is a directory"),
    ):
        code, out, err = run_cli(["track", "show", "trackdrive", "--out", str(out_file)], capsys)
        assert_bad_input(code, out, err, f"--out {out_file}: ", message)

    def refuse(self: Figure, fname: object, **kwargs: object) -> None:
        raise PermissionError(13, "Permission denied", str(fname))

    monkeypatch.setattr(Figure, "savefig", refuse)
    out_file = tmp_path / "new" / "sub" / "x.png"
    code, out, err = run_cli(["track", "show", "trackdrive", "--out", str(out_file)], capsys)
    assert_bad_input(code, out, err, f"--out {out_file}: ", "Permission denied")
    assert ".tmp" not in err
    assert not (tmp_path / "new").exists()


def test_run_start_pose_out_of_range_writes_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A start pose at 1e9 m: one line naming the file and the start pose, no --out directory."""
    source = Path(load_track("trackdrive").source or "").read_text().splitlines()
    path = tmp_path / "huge.yaml"
    path.write_text(
        "\n".join(
            "start_pose: [1.0e9, 0, 0]" if line.startswith("start_pose:") else line
            for line in source
            if not line.startswith("global_path:")
        )
    )
    out_dir = tmp_path / "run"
    code, out, err = run_cli(["run", "--track", str(path), "--out", str(out_dir)], capsys)
    assert_bad_input(code, out, err, f"{path}: start pose")
    assert not out_dir.exists()


def test_run_world_build_failure_names_the_track(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A geodesy error while the world is built names the track file and its start pose."""

    def unbuildable(*args: object, **kwargs: object) -> None:
        raise GeodesyError("local_cartesian_to_gps: longitude out of range [-180, 180] deg: 1e4")

    monkeypatch.setattr(scenario, "ClosedLoop", unbuildable)
    path = tmp_path / "fssim.yaml"
    write_fssim(path)
    out_dir = tmp_path / "run"
    code, out, err = run_cli(["run", "--track", str(path), "--out", str(out_dir)], capsys)
    assert_bad_input(
        code, out, err, f"{path}: cannot build the world at the start pose (", "longitude"
    )
    assert not out_dir.exists()


def test_run_result_json_as_directory_is_refused_before_simulating(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """--out DIR whose result.json is a directory: exit 2 before the run, nothing written."""

    def no_run(*args: object, **kwargs: object) -> None:
        raise AssertionError("simulated despite bad output directory")

    monkeypatch.setattr(runner, "run_scenario", no_run)
    (tmp_path / "run" / "result.json").mkdir(parents=True)
    code, out, err = run_cli(["run", "--out", str(tmp_path / "run")], capsys)
    assert_bad_input(code, out, err, "result.json is a directory")
    assert [p.name for p in (tmp_path / "run").iterdir()] == ["result.json"]


def test_outputs_are_both_or_nothing(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """When the second move fails, the first output and the created directories are removed."""
    monkeypatch.setattr(
        cli, "save_run_picture", lambda result, track, path, out: out.write_bytes(b"png")
    )
    real_replace = os.replace

    def replace(src: Path, dst: Path) -> None:
        # Moving the new result.json in fails; putting an old one back works.
        if Path(dst).name == "result.json" and ".old." not in Path(src).name:
            raise IsADirectoryError(21, "Is a directory", str(src))
        real_replace(src, dst)

    monkeypatch.setattr(os, "replace", replace)
    out_dir = tmp_path / "new" / "run"
    with pytest.raises(cli.CliError, match=r"cannot write the results \(Is a directory\)"):
        cli._write_outputs(
            out_dir, "{}", cast(RunResult, None), cast(Track, None), cast(GlobalPath, None)
        )
    assert list(tmp_path.iterdir()) == []
    monkeypatch.setattr(os, "replace", real_replace)
    cli._write_outputs(
        out_dir, "{}", cast(RunResult, None), cast(Track, None), cast(GlobalPath, None)
    )
    assert sorted(p.name for p in out_dir.iterdir()) == ["result.json", "run.png"]
    # A previous pair stays whole when the new one cannot be moved in.
    (out_dir / "result.json").write_text("old json")
    (out_dir / "run.png").write_bytes(b"old png")
    monkeypatch.setattr(os, "replace", replace)
    monkeypatch.setattr(
        cli, "save_run_picture", lambda result, track, path, out: out.write_bytes(b"new png")
    )
    with pytest.raises(cli.CliError, match="cannot write the results"):
        cli._write_outputs(
            out_dir, "{}", cast(RunResult, None), cast(Track, None), cast(GlobalPath, None)
        )
    monkeypatch.setattr(os, "replace", real_replace)
    assert sorted(p.name for p in out_dir.iterdir()) == ["result.json", "run.png"]
    assert (out_dir / "run.png").read_bytes() == b"old png"
    assert (out_dir / "result.json").read_text() == "old json"


@pytest.mark.skipif(not Path("/dev/zero").exists(), reason="needs a /dev/zero device")
def test_device_file_as_track_exits_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """/dev/zero is not a track file: one line, no MemoryError, nothing written."""
    for args in (
        ["track", "check", "/dev/zero"],
        ["run", "--track", "/dev/zero", "--out", str(tmp_path / "run")],
    ):
        code, out, err = run_cli(args, capsys)
        assert_bad_input(code, out, err, "/dev/zero: not a regular file")
    assert not (tmp_path / "run").exists()


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["run", "--track", ""], "--track: empty track name"),
        (["track", "check", ""], "empty track name"),
        (["track", "show", "", "--out", "x.png"], "empty track name"),
        (["run", "--out", ""], "--out: empty directory name"),
        (["track", "show", "trackdrive", "--out", ""], "--out: empty file name"),
    ],
)
def test_empty_names_are_refused(
    args: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """An empty track or output name is bad input with a clear line (not '.: is a directory')."""
    code, out, err = run_cli(args, capsys)
    assert_bad_input(code, out, err, message)


def make_result(lap_times: list[float], limit: float = 14.94, centre: float = 16.5) -> RunResult:
    """A RunResult with the given laps of a 1-lap run and neutral other fields."""
    best = min(lap_times) if lap_times else None
    return RunResult(
        track="trackdrive", seed=0, sensors="rtk", localization="fused", laps=1,
        finished=bool(lap_times), end_reason="laps" if lap_times else "off_track",
        laps_completed=len(lap_times), lap_times_s=lap_times, best_lap_s=best,
        cones_hit=0, cones_down_or_out=0, off_track_events=0, sim_time_s=1.0,
        wall_time_s=1.0, real_time_factor=1.0, setup_time_s=0.5, localization_pos_rmse_m=None,
        localization_yaw_rmse_deg=None, midline_rmse_m=None, planner_fallbacks=0,
        limit_lap_time_s=limit, centreline_lap_time_s=centre,
        lap_time_ratio=None if best is None else best / limit,
    )  # fmt: skip


def test_results_table_text() -> None:
    """No lap: 'none' without a unit and 'n/a'; a lap: seconds and the ratio as '1.14x'."""
    table = format_result(make_result([]), Path("out"))
    assert "laps               0/1: none\n" in table
    assert "limit lap          14.94 s (best lap n/a); centreline 16.50 s\n" in table
    assert "localization RMSE  n/a, n/a\n" in table and "midline RMSE       n/a\n" in table
    table = format_result(make_result([17.03]), Path("out"))
    assert "1/1: 17.03 s\n" in table
    assert "(best lap 1.14x)" in table
    table = format_result(make_result([]), Path("out"), "bag", saved_map=Path("map.yaml"))
    assert table.endswith("written            out/result.json, out/run.png, bag, map.yaml")


def test_a_reader_that_goes_away_ends_the_command_quietly(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """`conesim tracks | head -1`: writing into the closed pipe raises
    BrokenPipeError; the command ends with 141 (128 + SIGPIPE) and no traceback,
    and stdout is pointed at the null device for Python's flush at exit."""

    class ClosedPipe:
        def __init__(self, fd: int) -> None:
            self.fd = fd

        def write(self, text: str) -> int:
            raise BrokenPipeError(32, "Broken pipe")

        def flush(self) -> None:
            pass

        def fileno(self) -> int:
            return self.fd

    with (tmp_path / "stdout").open("w") as stand_in:
        monkeypatch.setattr("sys.stdout", ClosedPipe(stand_in.fileno()))
        assert main(["tracks"]) == cli.EXIT_BROKEN_PIPE == 141
    assert capsys.readouterr().err == ""


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["run", "", "--out", "o"], "empty scenario file name"),
        (["scenario", "show", ""], "empty scenario file name"),
        (["run", "--bag", "", "--out", "o"], "--bag (empty name): give the bag directory"),
        (["sweep", "", "--out", "o"], "sweep: empty sweep file name"),
    ],
)
def test_an_empty_name_is_named_as_empty(
    args: list[str],
    message: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """An empty file or directory name: one line saying so (not 'is a directory'), exit 2."""
    monkeypatch.chdir(tmp_path)
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"conesim: error: {message}") and err.count("\n") == 1, err
    assert list(tmp_path.iterdir()) == []


def test_ctrl_c_during_a_run_is_one_line_130_and_writes_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Ctrl-C at the 50th step of a run with a bag: exit 130 (128 + SIGINT), one
    line, no --out directory and nothing left of the bag (its temporary one included)."""
    step = ClosedLoop.step
    calls = []

    def interrupted(self: ClosedLoop) -> object:
        calls.append(1)
        if len(calls) == 50:
            raise KeyboardInterrupt
        return step(self)

    monkeypatch.setattr(ClosedLoop, "step", interrupted)
    args = ["run", "--track", "skidpad", "--out", str(tmp_path / "o"), "--bag", str(tmp_path / "b")]
    assert main(args) == cli.EXIT_INTERRUPTED == 130
    assert capsys.readouterr().err == "conesim: interrupted; nothing written\n"
    assert list(tmp_path.iterdir()) == []


def test_commands_other_than_run_load_no_compiled_kernels() -> None:
    """`--help`, `tracks` and `track check` import neither numba nor the closed
    loop: they start faster and print no cache warnings where numba has no
    writable cache directory."""
    code = (
        "import sys, contextlib, io\n"
        "from conesim.envs.cli import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    assert main(['tracks']) == 0 and main(['track', 'check', 'skidpad']) == 0\n"
        "loaded = sorted(m for m in sys.modules if m.split('.')[0] == 'numba'"
        " or m in ('conesim.envs.runner', 'conesim.envs.loop', 'conesim.planner'))\n"
        "assert not loaded, loaded\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
