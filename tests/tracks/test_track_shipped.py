"""The shipped tracks: found, valid, with the promised features and global paths."""

from __future__ import annotations

import importlib.util
import math
import sys
from pathlib import Path

import numpy as np
import pytest

from conesim.core.polyline import Polyline
from conesim.tracks import DEFAULT_TRACK, ConeKind, Layout, check_report, load_track, shipped_tracks
from conesim.tracks.global_path import COV_THRESHOLD_M2, read_global_path_csv

ROOT = Path(__file__).resolve().parents[2]


def test_shipped_names() -> None:
    """Four tracks, sorted, the default among them."""
    assert shipped_tracks() == ["acceleration", "autocross", "skidpad", "trackdrive"]
    assert DEFAULT_TRACK == "trackdrive"


@pytest.mark.parametrize("name", shipped_tracks())
def test_shipped_track_validates_without_errors(name: str) -> None:
    """Every shipped track loads and passes the validator: no errors, no warnings."""
    report = check_report(load_track(name))
    assert report["errors"] == []
    assert report["warnings"] == []
    assert report["width_min_m"] >= 3.0


def test_trackdrive_is_a_comfortable_default() -> None:
    """Closed, 250-300 m, 3.5-4 m wide, no corner tighter than 10 m radius."""
    track = load_track("trackdrive")
    assert track.layout == Layout.CLOSED
    assert 250.0 <= track.length_m <= 300.0
    assert track.widths.min() >= 3.5
    assert track.widths.max() <= 4.0
    assert np.abs(track.geometry.curvature).max() < 1.0 / 10.0


def test_autocross_features() -> None:
    """Closed, 250-400 m, a hairpin >= 9 m outside diameter, a straight of 60-80 m."""
    track = load_track("autocross")
    assert track.layout == Layout.CLOSED
    assert 250.0 <= track.length_m <= 400.0
    kappa = np.abs(track.geometry.curvature)
    tightest = int(np.argmax(kappa))
    outside = 2.0 * (1.0 / kappa[tightest] + track.widths[tightest] / 2)
    assert 9.0 <= outside <= 20.0
    # the corner around the tightest point turns ~180 deg: a hairpin
    signed = track.geometry.curvature * np.sign(track.geometry.curvature[tightest])
    corner = np.roll(signed >= 1.0 / 150.0, -tightest).astype(int)
    end = int(np.argmin(corner))
    start = len(corner) - int(np.argmin(corner[::-1]))
    turn = np.roll(signed, -tightest)[np.r_[0:end, start : len(corner)]].sum() * 0.5
    assert turn == pytest.approx(math.pi, abs=0.2)
    # the longest straight (curvature below 1/150 m, counted from the hairpin so that
    # the straight through the start line is one run) is 60-80 m
    straight = np.roll(kappa < 1.0 / 150.0, -tightest).astype(int)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], straight, [0]])))
    longest = (edges[1::2] - edges[::2]).max() * track.length_m / len(kappa)
    assert 60.0 <= longest <= 80.0


def test_acceleration_layout() -> None:
    """Open, 3.8 m wide, start line at 0 m, finish at 75 m, orange braking zone to 175 m."""
    track = load_track("acceleration")
    assert track.layout == Layout.OPEN
    np.testing.assert_allclose(track.widths, 3.8, atol=0.01)
    np.testing.assert_allclose(track.start_finish, [[0.0, 1.9], [0.0, -1.9]])
    np.testing.assert_allclose(track.finish_line, [[75.0, 1.9], [75.0, -1.9]])
    assert track.centreline[-1, 0] == pytest.approx(175.0, abs=0.01)
    assert track.counts()[ConeKind.BIG_ORANGE] == 8
    assert track.cones_of(ConeKind.ORANGE)[:, 0].min() >= 75.0


def test_skidpad_layout() -> None:
    """FS circles (cone centres 0.15 m off the 15.25 / 21.25 m lines), 18.25 m apart."""
    track = load_track("skidpad")
    assert track.geometry.circles is not None
    right, left = track.geometry.circles
    assert np.hypot(*(right.centre - left.centre)) == pytest.approx(18.25, abs=1e-6)
    assert 2 * right.r_inner == pytest.approx(15.25 - 0.3, abs=1e-6)
    assert 2 * left.r_outer == pytest.approx(21.25 + 0.3, abs=1e-6)
    assert right.centre[1] < 0 < left.centre[1]  # entry heads east: right circle to the south


@pytest.mark.parametrize("name", shipped_tracks())
def test_global_path_follows_the_centreline(name: str) -> None:
    """The lat,lon,cov CSV projects onto the centreline; covariance varies and crosses 0.0025."""
    track = load_track(name)
    assert track.global_path_file is not None and track.global_path_file.is_file()
    path = read_global_path_csv(track.global_path_file)
    lateral = Polyline(track.centreline, track.geometry.closed).project(path.xy).lateral
    assert np.abs(lateral).max() < 1e-6
    assert path.cov.min() < COV_THRESHOLD_M2 < path.cov.max()
    assert 0.05 < path.high_covariance.mean() < 0.5


def test_generator_reproduces_the_shipped_files(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """scripts/make_tracks.py writes exactly the files in tracks/data."""
    spec = importlib.util.spec_from_file_location(
        "make_tracks", ROOT / "scripts" / "make_tracks.py"
    )
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    monkeypatch.setitem(sys.modules, "make_tracks", module)  # dataclasses look themselves up
    spec.loader.exec_module(module)
    assert module.main(["--out", str(tmp_path)]) == 0
    data = ROOT / "tracks" / "data"
    shipped = sorted(p.name for p in data.iterdir() if p.suffix in (".yaml", ".csv"))
    assert sorted(p.name for p in tmp_path.iterdir()) == shipped
    for name in shipped:
        assert (tmp_path / name).read_bytes() == (data / name).read_bytes(), name
