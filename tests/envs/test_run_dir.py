"""Tests for envs.run_dir: which --out directories a run may write into."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from conesim.envs.run_dir import RunDirError, check_run_dir, is_previous_run


def previous_run(directory: Path) -> Path:
    """A directory as a run leaves it (a result.json conesim wrote, run.png)."""
    directory.mkdir(parents=True, exist_ok=True)
    (directory / "result.json").write_text(json.dumps({"track": "x", "end_reason": "stuck"}))
    (directory / "run.png").write_bytes(b"png")
    return directory


def test_new_empty_and_previous_runs_are_accepted(tmp_path: Path) -> None:
    """A new path (parents too), an empty directory, a previous run's with the
    user's own files beside it, and a folder holding only the scenario run."""
    check_run_dir(tmp_path / "new" / "deeper")
    (tmp_path / "empty").mkdir()
    check_run_dir(tmp_path / "empty")
    run = previous_run(tmp_path / "run")
    (run / "notes.txt").write_text("mine")
    (run / "bag").mkdir()
    check_run_dir(run)
    (tmp_path / "mine").mkdir()
    scenario = tmp_path / "mine" / "s.yaml"
    scenario.write_text("laps: 1\n")
    check_run_dir(tmp_path / "mine", scenario=scenario)
    (tmp_path / "mine" / ".result.json.123.tmp").write_text("")  # an interrupted write's
    check_run_dir(tmp_path / "mine", scenario=scenario)


@pytest.mark.parametrize(
    ("layout", "message"),
    [
        ("root", "/: is the root directory; give a directory for the run"),
        ("foreign", "holds other files (a.py, b.py, c.py, ...) and no previous run's result.json"),
        ("other json", "holds other files (x.txt) and no previous run's result.json"),
        ("file", "is not a directory"),
        ("under file", "is not a directory"),
        ("result dir", "result.json is a directory, not a file"),
        ("same as bag", "is --bag's directory or inside it; give each its own"),
        ("inside bag", "is --bag's directory or inside it"),
    ],
)
def test_refused_places_name_the_reason(layout: str, message: str, tmp_path: Path) -> None:
    """The root, a directory of other things (a result.json that is not a run's
    does not count), a file, a result.json directory, and --bag's directory."""
    out, bag = tmp_path / "out", None
    if layout == "root":
        out = Path(os.path.abspath(os.sep))
    elif layout == "foreign":
        out.mkdir()
        for name in ("a.py", "b.py", "c.py", "d.py"):
            (out / name).write_text("")
    elif layout == "other json":
        out.mkdir()
        (out / "result.json").write_text('{"loss": 0.1}')
        (out / "x.txt").write_text("")
    elif layout == "file":
        out.write_text("a file")
    elif layout == "under file":
        out.write_text("a file")
        out = out / "sub"
    elif layout == "result dir":
        (out / "result.json").mkdir(parents=True)
    elif layout == "same as bag":
        bag = out
    elif layout == "inside bag":
        bag, out = out, out / "results"
    with pytest.raises(RunDirError) as info:
        check_run_dir(out, bag=bag)
    assert message in str(info.value)


def test_a_previous_run_is_known_by_its_result(tmp_path: Path) -> None:
    """Only a JSON object with track and end_reason is a run's result.json."""
    assert is_previous_run(previous_run(tmp_path / "run"))
    (tmp_path / "bad").mkdir()
    (tmp_path / "bad" / "result.json").write_text("not json")
    assert not is_previous_run(tmp_path / "bad")
    assert not is_previous_run(tmp_path / "missing")
