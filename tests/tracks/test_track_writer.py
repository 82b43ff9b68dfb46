"""The writer: exact round trips and atomic replacement."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
import yaml

from conesim.core.pose import Pose2D
from conesim.tracks import ConeKind, Track, load_track, read_track, shipped_tracks, write_track


@pytest.mark.parametrize("name", shipped_tracks())
def test_round_trip_of_shipped_tracks(tmp_path: Path, name: str) -> None:
    """Write then read: equal track, same geometry, global path still found."""
    track = load_track(name)
    back = read_track(write_track(track, tmp_path / "copy.yaml"))
    assert back == track
    np.testing.assert_array_equal(back.cones, track.cones)
    assert back.kinds == track.kinds and back.start_pose == track.start_pose
    np.testing.assert_array_equal(back.centreline, track.centreline)
    # The shipped global path is copied next to the written track, byte for byte.
    assert back.global_path_file == tmp_path / "copy_path.csv"
    assert track.global_path_file is not None
    assert back.global_path_file.read_bytes() == track.global_path_file.read_bytes()
    assert yaml.safe_load((tmp_path / "copy.yaml").read_text())["global_path"] == "copy_path.csv"


def test_a_shipped_global_path_copy_never_replaces_another_file(tmp_path: Path) -> None:
    """Writing again keeps the identical copy; replacing the track file with
    another shipped track replaces its copy too; a different file of that
    name that no replaced track names is refused before anything is created."""
    skidpad, lane = load_track("skidpad"), load_track("acceleration")
    write_track(skidpad, tmp_path / "mine.yaml")
    write_track(skidpad, tmp_path / "mine.yaml")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mine.yaml", "mine_path.csv"]
    write_track(lane, tmp_path / "mine.yaml")
    assert lane.global_path_file is not None
    assert (tmp_path / "mine_path.csv").read_bytes() == lane.global_path_file.read_bytes()
    assert read_track(tmp_path / "mine.yaml") == lane
    (tmp_path / "other_path.csv").write_text("37.5,127.0,0.001\n")
    with pytest.raises(FileExistsError, match=r"other_path\.csv: exists and is not the global"):
        write_track(skidpad, tmp_path / "deep" / ".." / "other.yaml")
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "mine.yaml", "mine_path.csv", "other_path.csv"
    ]  # fmt: skip
    assert (tmp_path / "other_path.csv").read_text() == "37.5,127.0,0.001\n"


def test_a_failed_write_removes_the_global_path_copy_it_made(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The copy is written first; when the track file then cannot be moved into
    place, the copy goes again (or the copy it replaced comes back)."""
    real_replace = os.replace

    def replace(src: str, dst: str) -> None:
        if str(dst).endswith(".yaml"):
            raise OSError("disk full")
        real_replace(src, dst)

    monkeypatch.setattr(os, "replace", replace)
    with pytest.raises(OSError, match="disk full"):
        write_track(load_track("acceleration"), tmp_path / "lane.yaml")
    assert list(tmp_path.iterdir()) == []
    monkeypatch.setattr(os, "replace", real_replace)
    write_track(load_track("skidpad"), tmp_path / "lane.yaml")
    before = (tmp_path / "lane_path.csv").read_bytes()
    monkeypatch.setattr(os, "replace", replace)
    with pytest.raises(OSError, match="disk full"):
        write_track(load_track("acceleration"), tmp_path / "lane.yaml")
    assert (tmp_path / "lane_path.csv").read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["lane.yaml", "lane_path.csv"]


def test_round_trip_is_exact_for_awkward_floats(tmp_path: Path, stadium) -> None:
    """Floats that do not print short (1/3, 1e-17 offsets) come back bit for bit."""
    base = stadium()
    rng = np.random.default_rng(0)
    cones = base.cones + rng.uniform(-1e-3, 1e-3, base.cones.shape) / 3.0
    order = rng.permutation(len(cones))  # interleaved kinds: stored grouped by kind
    pose = Pose2D(6.0 + 1e-15, -15.0 + 1.0 / 3.0 * 1e-9, 1e-17)
    track = Track(
        "awkward",
        cones[order],
        tuple(base.kinds[i] for i in order),
        pose,
        description="a track: with 'quotes', colons and unicode \u00b0",
    )
    back = read_track(write_track(track, tmp_path / "awkward.yaml"))
    assert back == track
    assert back.description == track.description


def test_written_document_shape(tmp_path: Path, stadium) -> None:
    """The file is our format: version, name, layout, start pose, cones by kind."""
    path = write_track(stadium(), tmp_path / "s.yaml")
    doc = yaml.safe_load(path.read_text())
    assert list(doc) == ["conesim_track", "name", "layout", "start_pose", "global_path", "cones"]
    assert doc["conesim_track"] == 1 and doc["layout"] == "closed"
    assert doc["start_pose"] == [6.0, -15.0, 0.0]
    assert set(doc["cones"]) == {"blue", "yellow", "big_orange"}
    assert oct(path.stat().st_mode & 0o777) != "0o600"  # not mkstemp's private mode


def test_write_is_atomic(tmp_path: Path, stadium, monkeypatch: pytest.MonkeyPatch) -> None:
    """A failure while writing leaves the old file untouched and no temporary file behind."""
    target = tmp_path / "track.yaml"
    target.write_text("old content\n")

    def broken_replace(src: str, dst: str) -> None:
        raise OSError("disk full")

    monkeypatch.setattr(os, "replace", broken_replace)
    with pytest.raises(OSError, match="disk full"):
        write_track(stadium(), target)
    assert target.read_text() == "old content\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["track.yaml"]


def test_global_path_written_relative(tmp_path: Path, stadium) -> None:
    """A global path next to the output is written as its bare name."""
    path_csv = tmp_path / "s_path.csv"
    path_csv.write_text("37.5,127.0,0.001\n37.50001,127.0,0.001\n")
    base = stadium()
    track = Track(
        base.name, base.cones, base.kinds, base.start_pose, base.layout, global_path_file=path_csv
    )
    out = write_track(track, tmp_path / "s.yaml")
    assert yaml.safe_load(out.read_text())["global_path"] == "s_path.csv"
    assert read_track(out).global_path_file == path_csv
    assert ConeKind.BLUE in read_track(out).counts()
