"""Tests for localization.global_path: the ROS pipeline's lat,lon,cov CSV."""

from __future__ import annotations

import contextlib
import os
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from conesim.core.geodesy import DEFAULT_ORIGIN, local_cartesian_to_gps
from conesim.tracks.global_path import (
    COV_THRESHOLD_M2,
    GlobalPath,
    GlobalPathError,
    global_path_findings,
    global_path_for_track,
    global_path_from_centreline,
    read_global_path_csv,
    write_global_path_csv,
)


def circle(radius: float = 20.0, n: int = 100) -> np.ndarray:
    """A counter-clockwise circle of ``n`` points."""
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.column_stack([radius * np.cos(t), radius * np.sin(t)])


def test_csv_round_trip_reproduces_points(tmp_path: Path) -> None:
    """Writing then reading a derived path gives the same xy to 1e-6 m and the cov exactly."""
    xy = circle()
    cov = np.where(np.arange(100) < 30, 0.01, 0.0004)
    path = global_path_from_centreline(xy, closed=True, cov=cov)
    write_global_path_csv(tmp_path / "p.csv", path)
    back = read_global_path_csv(tmp_path / "p.csv")
    assert_allclose(back.xy, xy, atol=1e-6)
    assert_allclose(back.cov, cov)
    assert back.closed
    assert_allclose(back.polyline.length, 100 * 2 * 20 * np.sin(np.pi / 100), rtol=1e-9)


def test_status_is_red_above_seed_threshold(tmp_path: Path) -> None:
    """cov > 0.0025 m^2 is red, otherwise green (the ROS pipeline's rule)."""
    lat, lon = local_cartesian_to_gps(np.array([0.0, 10.0, 20.0]), np.zeros(3))
    rows = [
        f"{lat[0]},{lon[0]},0.0025",
        f"{lat[1]},{lon[1]},0.0026",
        f"{lat[2]},{lon[2]},0.0001",
    ]
    (tmp_path / "p.csv").write_text("lat,lon,cov\n" + "\n".join(rows) + "\n")
    path = read_global_path_csv(tmp_path / "p.csv")
    assert COV_THRESHOLD_M2 == 0.0025
    assert path.status == ["green", "red", "green"]
    assert_allclose(path.xy[:, 0], [0.0, 10.0, 20.0], atol=1e-9)
    assert not path.closed


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("", "at least 2 points"),
        ("37.54,127.07,0.1\n", "at least 2 points"),
        ("37.54,127.07\n", ":1: expected 3 columns"),
        ("37.54,127.07,0.1\n37.55,127.07,0.1,9\n", ":2: expected 3 columns"),
        ("37.54,abc,0.1\n37.55,127.07,0.1\n", ":1: column 'lon': 'abc' is not a number"),
        ("37.54,127.07,nan\n37.55,127.07,0.1\n", ":1: column 'cov': 'nan' is not finite"),
        ("97.54,127.07,0.1\n37.55,127.07,0.1\n", ":1: column 'lat': 97.54 is outside"),
        ("37.54,227.07,0.1\n37.55,127.07,0.1\n", ":1: column 'lon': 227.07 is outside"),
        ("37.54,127.07,-1\n37.55,127.07,0.1\n", ":1: column 'cov': -1.0 is negative"),
        ("37.54,127.07,0.1\n37.54,127.07,0.2\n", ":2: point repeats"),
    ],
)
def test_malformed_csv_names_file_and_line(tmp_path: Path, content: str, message: str) -> None:
    """Each malformation raises GlobalPathError naming the file, line and problem."""
    f = tmp_path / "bad.csv"
    f.write_text(content)
    with pytest.raises(GlobalPathError, match=message) as info:
        read_global_path_csv(f)
    assert str(f) in str(info.value)


def test_binary_and_missing_files(tmp_path: Path) -> None:
    """A binary file and a missing file get one clear GlobalPathError."""
    f = tmp_path / "bin.csv"
    f.write_bytes(b"\x00\x01\x02\xff")
    with pytest.raises(GlobalPathError, match="binary"):
        read_global_path_csv(f)
    with pytest.raises(GlobalPathError, match="cannot read"):
        read_global_path_csv(tmp_path / "missing.csv")


def test_writer_leaves_no_partial_file(tmp_path: Path) -> None:
    """The writer replaces the target atomically; no temporary file is left behind."""
    path = global_path_from_centreline(circle(), closed=True)
    target = tmp_path / "out" / "p.csv"
    write_global_path_csv(target, path)
    assert [p.name for p in target.parent.iterdir()] == ["p.csv"]
    assert target.read_text().count("\n") == 100


@settings(max_examples=200, deadline=None)
@given(st.binary(max_size=300))
def test_fuzz_reader_only_raises_global_path_error(
    tmp_path_factory: pytest.TempPathFactory, data: bytes
) -> None:
    """Arbitrary bytes either parse or raise GlobalPathError, never anything else."""
    f = tmp_path_factory.mktemp("fuzz") / "f.csv"
    f.write_bytes(data)
    with contextlib.suppress(GlobalPathError):
        read_global_path_csv(f)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.text(alphabet="0123456789.,-eE\nnaif ", max_size=30), max_size=6))
def test_fuzz_reader_text(tmp_path_factory: pytest.TempPathFactory, lines: list[str]) -> None:
    """CSV-like text either parses or raises GlobalPathError."""
    f = tmp_path_factory.mktemp("fuzz") / "f.csv"
    f.write_text(f"{DEFAULT_ORIGIN.lat_deg},{DEFAULT_ORIGIN.lon_deg},0.1\n" + "\n".join(lines))
    with contextlib.suppress(GlobalPathError):
        read_global_path_csv(f)


def test_written_file_has_ordinary_permissions(tmp_path: Path) -> None:
    """The atomic writer leaves a 0644 file under umask 022 (not mkstemp's 0600)."""
    old = os.umask(0o022)
    try:
        write_global_path_csv(tmp_path / "p.csv", global_path_from_centreline(circle(), True))
    finally:
        os.umask(old)
    assert (tmp_path / "p.csv").stat().st_mode & 0o777 == 0o644


def test_findings_against_the_track() -> None:
    """trackdrive's own path fits it; moved 10 m (more than half its widest
    width plus 1 m) it is an error, the car would follow another line; one
    point 20 m off (a bad fix) is a warning naming it."""
    from conesim.tracks import load_track

    track = load_track("trackdrive")
    path = global_path_for_track(track)
    assert global_path_findings(track, path) == ([], [])
    limit = 0.5 * float(np.max(track.widths)) + 1.0
    moved = global_path_from_centreline(path.xy + np.array([10.0, 0.0]), closed=True)
    warnings, errors = global_path_findings(track, moved)
    assert any(f"points lie more than {limit:.1f} m" in e for e in errors)
    assert any("does not follow the track" in e for e in errors)
    xy = path.xy.copy()
    xy[40] += [0.0, 20.0]
    warnings, errors = global_path_findings(track, global_path_from_centreline(xy, closed=True))
    x, y = xy[40]
    assert errors == [] and len(warnings) == 1
    assert f"1 of {len(xy)} points" in warnings[0] and f"({x:.1f}, {y:.1f})" in warnings[0]


def test_global_path_copies_the_callers_arrays() -> None:
    """The path's arrays are read-only copies: the caller's stay writeable and
    changing them afterwards does not move the path."""
    xy, cov = circle(), np.full(100, 1e-4)
    lat, lon = local_cartesian_to_gps(xy[:, 0], xy[:, 1], DEFAULT_ORIGIN)
    path = GlobalPath(xy=xy, cov=cov, lat=lat, lon=lon, closed=True)
    assert xy.flags.writeable and cov.flags.writeable and lat.flags.writeable
    xy[0, 0] = 99.0
    assert path.xy[0, 0] == 20.0 and not path.xy.flags.writeable


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"xy_nan": 3}, "xy of point 3 is not finite"),
        ({"repeat": 5}, "point 5 repeats the one before it"),
        ({"cov": -1.0}, "cov of point 0 is negative"),
        ({"lat_short": True}, r"lat and lon \(n,\)"),
    ],
)
def test_global_path_rejects_what_no_path_can_be(change: dict[str, object], message: str) -> None:
    """NaN points, a point repeated (a zero-length segment), a negative
    covariance and lat/lon of another length are named, not met later deep in numpy."""
    xy, cov = circle(), np.full(100, 1e-4)
    lat, lon = local_cartesian_to_gps(xy[:, 0], xy[:, 1], DEFAULT_ORIGIN)
    if "xy_nan" in change:
        xy[3, 1] = np.nan
    if "repeat" in change:
        xy[5] = xy[4]
    if "cov" in change:
        cov[0] = -1.0
    if "lat_short" in change:
        lat = lat[:-1]
    with pytest.raises(GlobalPathError, match=message):
        GlobalPath(xy=xy, cov=cov, lat=lat, lon=lon, closed=True)


def test_centreline_of_three_columns_rejected() -> None:
    """An (n, 3) x, y, z array is refused by shape, not read as a zig-zag of (n * 3 / 2) points."""
    with pytest.raises(GlobalPathError, match=r"must be \(n, 2\) \[m\], got \(4, 3\)"):
        global_path_from_centreline(np.zeros((4, 3)), closed=False)
