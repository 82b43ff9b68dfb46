"""Sweep files: expansion into runs; every validation error is one line, exit 2, nothing written."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from conesim.envs.cli import main
from conesim.envs.dataclass_io import FieldError
from conesim.envs.scenario_file import load_scenario
from conesim.envs.sweep_file import BASE_LABEL, load_sweep
from tests.envs.sweep_helpers import copy_track


def write(tmp_path: Path, text: str, name: str = "sweep.yaml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def test_product_counts_and_order(tmp_path: Path) -> None:
    """2 tracks x 3 seeds x 2 fault levels = 12 runs, the last axis varying fastest."""
    sweep = load_sweep(
        write(
            tmp_path,
            """\
conesim_sweep: 1
base: {laps: 1, faults: {cones: {false_positives_per_scan: 0.5}}}
axes:
  track: [acceleration, skidpad]
  seed: {range: [0, 3]}
  faults:
    none: {}
    misses: {cones: {detection_probability: 0.7}}
""",
        )
    )
    assert sweep.axes == ("track", "seed", "faults")
    assert len(sweep.points) == 12
    assert [p.index for p in sweep.points] == list(range(12))
    assert sweep.points[0].labels == (("track", "acceleration"), ("seed", "0"), ("faults", "none"))
    assert sweep.points[1].labels == (
        ("track", "acceleration"),
        ("seed", "0"),
        ("faults", "misses"),
    )
    assert sweep.points[11].labels == (("track", "skidpad"), ("seed", "2"), ("faults", "misses"))
    last = sweep.points[11].scenario
    assert (last.track, last.seed) == ("skidpad", 2)
    # a level is merged into the base: the base's false positives stay
    assert last.faults.cones.detection_probability == 0.7
    assert last.faults.cones.false_positives_per_scan == 0.5
    assert sweep.points[10].scenario.faults.cones.detection_probability == 1.0
    ids = [p.run_id for p in sweep.points]
    assert len(set(ids)) == 12
    assert ids[11].startswith("track=skidpad_seed=2_faults=misses-")
    # the ids, and so the fingerprint, are the point's alone: the same on reloading
    assert load_sweep(tmp_path / "sweep.yaml").fingerprint == sweep.fingerprint


def test_list_of_points_and_range_step(tmp_path: Path) -> None:
    """3 points: the keys any sets are the axes, (base) where a point sets none; a stepped range."""
    sweep = load_sweep(
        write(
            tmp_path,
            """\
base: {track: skidpad}
points:
- {seed: 3}
- {seed: 4, sensors: consumer}
- {faults.cones.detection_probability: 0.7}
""",
        )
    )
    assert sweep.axes == ("seed", "sensors", "faults.cones.detection_probability")
    dp = "faults.cones.detection_probability"
    assert [dict(p.labels) for p in sweep.points] == [
        {"seed": "3", "sensors": BASE_LABEL, dp: BASE_LABEL},
        {"seed": "4", "sensors": "consumer", dp: BASE_LABEL},
        {"seed": BASE_LABEL, "sensors": BASE_LABEL, dp: "0.7"},
    ]
    assert sweep.points[1].scenario.sensors.name == "consumer"
    stepped = load_sweep(write(tmp_path, "axes: {seed: {range: [0, 10, 3]}}", "s2.yaml"))
    assert [p.scenario.seed for p in stepped.points] == [0, 3, 6, 9]


def test_point_is_the_scenario_set_would_make(tmp_path: Path) -> None:
    """An axis value is `--set`'s: the scenario equals load_scenario with that override."""
    write(tmp_path, "track: skidpad\nlaps: 2\n", "base.yaml")
    sweep = load_sweep(
        write(tmp_path, "base: base.yaml\naxes: {sensors.cones.max_range: [12.5]}\n")
    )
    expected = load_scenario(tmp_path / "base.yaml", {"sensors.cones.max_range": 12.5})
    assert sweep.points[0].scenario == expected


def test_track_files_are_relative_to_the_sweep_file(tmp_path: Path) -> None:
    """A track file named in the sweep file is found beside it, from any directory."""
    (tmp_path / "tracks").mkdir()
    copy_track("skidpad", tmp_path / "tracks" / "mine.yaml")
    sweep = load_sweep(write(tmp_path, "axes: {track: [tracks/mine.yaml]}\n"))
    assert sweep.points[0].scenario.track == str(tmp_path / "tracks" / "mine.yaml")


BAD = [
    ("nonsense: 1\naxes: {seed: [1]}\n", r"sweep.yaml:1: nonsense: unknown key 'nonsense'; "
     r"allowed keys: conesim_sweep, base, axes, points"),
    ("conesim_sweep: 2\naxes: {seed: [1]}\n", r"sweep.yaml:1: conesim_sweep: unknown format "
     r"version 2"),
    ("base: {}\n", r"give either axes \(their product\) or points \(a list\); it has neither"),
    ("axes: {seed: [1]}\npoints: [{seed: 1}]\n", r"give either axes .*; it has both"),
    ("axes: {}\n", r"sweep.yaml:1: axes: expected a mapping of dotted keys"),
    ("axes: {seed: 3}\n", r"sweep.yaml:1: axes.seed: expected a list of values"),
    ("axes: {seed: []}\n", r"axes.seed: has no values"),
    ("axes:\n  seed: [1, 1]\n", r"sweep.yaml:2: axes.seed\[1\]: value '1' given twice"),
    ("axes: {seed: {range: [5, 2]}}\n", r"axes.seed.range: \[5, 2\] is empty"),
    ("axes: {seed: {range: [0, 1.5]}}\n", r"axes.seed.range: expected \[start, stop\]"),
    ("axes: {seed: {range: [0, 9, 0]}}\n", r"axes.seed.range: step must not be 0"),
    ("axes: {seed: {range: [0, 200000]}}\n", r"axes.seed.range: 200000 values; at most 100000"),
    ("axes: {'a..b': [1]}\n", r"bad key 'a..b': expected names joined by dots"),
    ("axes:\n  faults.cones.detection_probability: [0.5, 1.5]\n",
     r"sweep.yaml:2: faults.cones.detection_probability: .*1.5 is out of range: allowed \[0, 1\]"),
    ("axes:\n  sensors.cones.maxrange: [20]\n",
     r"sweep.yaml:2: sensors.cones.maxrange: unknown key 'maxrange'; allowed keys: .*max_range"),
    ("base:\n  laps: two\naxes: {seed: [1]}\n",
     r"sweep.yaml:2: laps: expected an integer, got 'two' \(text\)"),
    ("base: 3\naxes: {seed: [1]}\n", r"sweep.yaml:1: base: expected a scenario file or a scenario"),
    ("base: missing.yaml\naxes: {seed: [1]}\n", r"missing.yaml: no such file"),
    ("points: [{seed: 1}, {seed: 1}]\n", r"runs 1 and 2 are the same run"),
    ("points: [3]\n", r"sweep.yaml:1: points\[0\]: expected a mapping of dotted keys, got 3"),
    ("points: []\n", r"points: expected a list of runs"),
    ("axes: {track: [nosuchtrack]}\n", r"'nosuchtrack' is neither a shipped track"),
    ("axes: [1, 2\n", r"sweep.yaml:\d+: not valid YAML"),
]  # fmt: skip


@pytest.mark.parametrize(("text", "message"), BAD)
def test_bad_sweep_file_is_one_line_exit_2_nothing_written(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str, message: str
) -> None:
    """Each problem: one line naming the file, line and key; exit 2; --out not made."""
    path = write(tmp_path, text)
    out = tmp_path / "out"
    assert main(["sweep", str(path), "--out", str(out)]) == 2
    captured = capsys.readouterr()
    lines = captured.err.splitlines()
    assert len(lines) == 1, captured.err
    assert lines[0].startswith("conesim: error: ")
    assert re.search(message, lines[0]), lines[0]
    assert "Traceback" not in captured.err
    assert not out.exists()
    with pytest.raises(FieldError):
        load_sweep(path)


def test_bad_command_line_is_one_line_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """--workers 0, no --out, --out / or a file or another sweep's directory: one line, exit 2."""
    path = write(tmp_path, "axes: {seed: [1]}\n")
    (tmp_path / "file").write_text("x")
    other = tmp_path / "other"
    other.mkdir()
    (other / "sweep.json").write_text(json.dumps({"conesim_sweep_dir": 1, "fingerprint": "x"}))
    (tmp_path / "notes").mkdir()
    (tmp_path / "notes" / "todo.txt").write_text("mine")
    (tmp_path / "broken").mkdir()
    (tmp_path / "broken" / "sweep.json").write_text('{"conesim_sweep_dir": 1, "finger')
    cases = [
        (["--out", str(tmp_path / "o"), "--workers", "0"], r"--workers 0: must be in \[1, 1024\]"),
        ([], r"--out DIR is required"),
        (["--out", "/"], r"--out /: is the root directory"),
        (["--out", str(tmp_path / "file")], r"is not a directory"),
        (["--out", str(other)], r"holds a sweep of other runs"),
        (["--out", str(tmp_path / "notes")], r"holds other files and no sweep.json"),
        (["--out", str(tmp_path / "broken")], r"holds a sweep.json conesim cannot read"),
        (["--out", str(tmp_path / "o"), "--workers", "x"], r"invalid int value: 'x'"),
        (["--out", str(tmp_path / "o"), "--ray", ""], r"--ray: empty address"),
    ]
    for args, message in cases:
        assert main(["sweep", str(path), *args]) == 2
        err = capsys.readouterr().err.splitlines()
        assert len(err) == 1 and re.search(message, err[0]), (args, err)
    assert main(["sweep", "summary", str(tmp_path / "o")]) == 2
    assert "no sweep.json: not a sweep's directory" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()
    assert sorted(p.name for p in other.iterdir()) == ["sweep.json"]
