"""Readers: each format on small files, detection by content, and every bad input."""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

from conesim.core.pose import Pose2D
from conesim.tracks import (
    ConeKind,
    Layout,
    TrackFileFormat,
    TrackFormatError,
    TrackNotFoundError,
    detect_format,
    load_track,
    read_track,
    readers,
    shipped_tracks,
)

EUFS_HEADER = "tag,x,y,direction,x_variance,y_variance,xy_covariance"


def lane_rows() -> list[tuple[str, float, float]]:
    """An acceleration-like lane: blue/yellow at +-1.9 m every 5 m from 5 to 30 m,
    big orange pairs at the start line (x = 0), orange at 35 and 40 m."""
    rows = []
    for x in (5.0, 10.0, 15.0, 20.0, 25.0, 30.0):
        rows += [("blue", x, 1.9), ("yellow", x, -1.9)]
    for x in (-0.3, 0.3):
        rows += [("big_orange", x, 1.9), ("big_orange", x, -1.9)]
    for x in (35.0, 40.0):
        rows += [("orange", x, 1.9), ("orange", x, -1.9)]
    return rows


def eufs_text(
    rows: list[tuple[str, float, float]], start: str = "car_start,-2.0,0.0,0.0,0.0,0.0,0.0"
) -> str:
    """An EUFS CSV: header, car_start row, one row per cone."""
    lines = [EUFS_HEADER, start] if start else [EUFS_HEADER]
    lines += [f"{tag},{x},{y},0.0,0.01,0.01,0.0" for tag, x, y in rows]
    return "\n".join(lines) + "\n"


def fsds_text(rows: list[tuple[str, float, float]]) -> str:
    """An FSDS CSV: no header, one row per cone."""
    return "".join(f"{tag},{x},{y},0,0,0,0\n" for tag, x, y in rows)


def write(tmp_path: Path, name: str, text: str | bytes) -> Path:
    """Write a file into tmp_path."""
    path = tmp_path / name
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(text)
    return path


OWN_YAML = """\
conesim_track: 1
name: lane
description: a small test lane
layout: open
start_pose: [-2.0, 0.0, 0.0]
global_path: null
cones:
  blue: [[5.0, 1.9], [10.0, 1.9], [15.0, 1.9], [20.0, 1.9]]
  yellow: [[5.0, -1.9], [10.0, -1.9], [15.0, -1.9], [20.0, -1.9]]
  big_orange: [[-0.3, 1.9], [0.3, 1.9], [-0.3, -1.9], [0.3, -1.9]]
"""

# Block style, as fssim's own tracks_yaml files are written (yaml.dump default).
FSSIM_YAML = """\
cones_left:
- - 5.0
  - 1.9
- - 10.0
  - 1.9
- - 15.0
  - 1.9
- - 20.0
  - 1.9
cones_orange: []
cones_orange_big:
- - -0.3
  - 1.9
- - -0.3
  - -1.9
- - 0.3
  - 1.9
- - 0.3
  - -1.9
cones_right:
- - 5.0
  - -1.9
- - 10.0
  - -1.9
- - 15.0
  - -1.9
- - 20.0
  - -1.9
starting_pose_front_wing:
- -2.0
- 0.0
- 0.087
tk_device:
- - 0.0
  - 2.4
- - 0.0
  - -2.4
"""


def test_own_format(tmp_path: Path) -> None:
    """Our YAML: name, layout, start pose, description and cones by kind."""
    track = read_track(write(tmp_path, "lane.yaml", OWN_YAML))
    assert track.name == "lane" and track.layout == Layout.OPEN
    assert track.description == "a small test lane"
    assert track.start_pose == Pose2D(-2.0, 0.0, 0.0)
    assert track.counts()[ConeKind.BIG_ORANGE] == 4
    assert track.global_path_file is None
    assert track.source == tmp_path / "lane.yaml"


def test_own_format_global_path_next_to_the_file(tmp_path: Path) -> None:
    """global_path names a file next to the track file."""
    write(tmp_path, "lane_path.csv", "37.5,127.0,0.001\n37.50001,127.0,0.001\n")
    text = OWN_YAML.replace("global_path: null", "global_path: lane_path.csv")
    track = read_track(write(tmp_path, "lane.yaml", text))
    assert track.global_path_file == tmp_path / "lane_path.csv"


def test_fssim(tmp_path: Path) -> None:
    """fssim YAML: left = blue, right = yellow, the front-wing start pose (the
    CG 1.515 m behind it), tk_device ignored."""
    track = read_track(write(tmp_path, "acceleration.yaml", FSSIM_YAML))
    assert track.name == "acceleration"
    assert track.layout == Layout.OPEN
    d = 1.515
    assert track.start_pose == Pose2D(-2.0 - d * math.cos(0.087), -d * math.sin(0.087), 0.087)
    assert_allclose(track.cones_of(ConeKind.BLUE)[:, 1], 1.9)
    assert_allclose(track.cones_of(ConeKind.YELLOW)[:, 1], -1.9)
    assert_allclose(track.start_finish, [[0.0, 1.9], [0.0, -1.9]])


def test_fssim_cg_pose(tmp_path: Path) -> None:
    """starting_pose_cg is the start pose when there is no front-wing pose."""
    text = FSSIM_YAML.replace("starting_pose_front_wing", "starting_pose_cg")
    assert read_track(write(tmp_path, "a.yaml", text)).start_pose == Pose2D(-2.0, 0.0, 0.087)


def test_eufs(tmp_path: Path) -> None:
    """EUFS CSV: car_start direction is the yaw; midpoint rows are ignored."""
    text = eufs_text(lane_rows(), "car_start,-2.0,0.0,0.1,0.0,0.0,0.0")
    text += "midpoint,12.5,0.0,0.0,0.0,0.0,0.0\n"
    track = read_track(write(tmp_path, "small_track.csv", text))
    assert track.start_pose == Pose2D(-2.0, 0.0, 0.1)
    assert track.counts() == {
        ConeKind.BLUE: 6,
        ConeKind.YELLOW: 6,
        ConeKind.ORANGE: 4,
        ConeKind.BIG_ORANGE: 4,
        ConeKind.UNKNOWN: 0,
    }
    assert track.layout == Layout.OPEN
    assert track.length_m == pytest.approx(40.3, abs=0.01)


def test_fsds_derives_the_start_pose(tmp_path: Path) -> None:
    """FSDS CSV: no header, no start pose: derived at the middle of the big orange cones."""
    track = read_track(write(tmp_path, "map.csv", fsds_text(lane_rows())))
    assert (track.start_pose.x, track.start_pose.y) == pytest.approx((0.0, 0.0), abs=1e-9)
    assert track.start_pose.yaw == pytest.approx(0.0, abs=1e-3)


def test_fsds_closed_loop(tmp_path: Path, stadium) -> None:
    """A loop in FSDS form is detected as closed and driven with blue on the left."""
    src = stadium()
    rows = [(str(k), float(x), float(y)) for (x, y), k in zip(src.cones, src.kinds, strict=True)]
    track = read_track(write(tmp_path, "loop.csv", fsds_text(rows)))
    assert track.layout == Layout.CLOSED
    assert track.start_pose.yaw == pytest.approx(0.0, abs=1e-3)
    assert track.length_m == pytest.approx(src.length_m, abs=1e-6)


@pytest.mark.parametrize(
    ("name", "text", "expected"),
    [
        ("eufs.txt", eufs_text(lane_rows()), TrackFileFormat.EUFS),
        ("cones", fsds_text(lane_rows()), TrackFileFormat.FSDS),
        ("track.csv", FSSIM_YAML, TrackFileFormat.FSSIM),
        ("track.txt", OWN_YAML, TrackFileFormat.CONESIM),
    ],
)
def test_detection_by_content(
    tmp_path: Path, name: str, text: str, expected: TrackFileFormat
) -> None:
    """The extension does not matter: an EUFS file named .txt is EUFS, YAML named .csv is YAML."""
    path = write(tmp_path, name, text)
    assert detect_format(text, path) == expected
    assert read_track(path).counts()[ConeKind.BLUE] >= 4


def test_skidpad_detected_from_fssim(tmp_path: Path, skidpad) -> None:
    """An fssim file with the skidpad's rings is read as a skidpad."""
    src = skidpad()
    keys = {
        ConeKind.BLUE: "cones_left",
        ConeKind.YELLOW: "cones_right",
        ConeKind.ORANGE: "cones_orange",
        ConeKind.BIG_ORANGE: "cones_orange_big",
    }
    lines = []
    for kind, key in keys.items():
        lines.append(f"{key}:")
        lines += [f"- [{float(x)!r}, {float(y)!r}]" for x, y in src.cones_of(kind)]
    start = src.start_pose  # the CG; the file gives the wing tip, 1.515 m ahead
    lines.append(f"starting_pose_front_wing: [{start.x + 1.515!r}, {start.y!r}, {start.yaw!r}]")
    track = read_track(write(tmp_path, "skidpad.yaml", "\n".join(lines) + "\n"))
    assert track.layout == Layout.SKIDPAD
    assert track.length_m == pytest.approx(src.length_m, abs=1e-9)


def test_error_names_file_line_and_column(tmp_path: Path) -> None:
    """The brief's example message, exactly."""
    rows = lane_rows()
    text = eufs_text(rows).splitlines()
    text[11] = "blue,abc,1.9,0.0,0.01,0.01,0.0"  # line 12
    path = write(tmp_path, "file.csv", "\n".join(text) + "\n")
    with pytest.raises(TrackFormatError) as info:
        read_track(path)
    assert str(info.value) == f"{path}:12: column 'x': 'abc' is not a number"
    assert info.value.line == 12 and info.value.path == str(path)


def _eufs_with(line_no: int, row: str) -> str:
    lines = eufs_text(lane_rows()).splitlines()
    lines[line_no - 1] = row
    return "\n".join(lines) + "\n"


ANY_LINE = -1  # the line a case's error names depends on the PyYAML release
BAD_FILES = [
    ("empty.csv", "", None, "empty file"),
    ("blank.yaml", "\n  \n", None, "empty file"),
    ("binary.csv", b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR", None, "binary file"),
    ("latin1.csv", "tag,x,y\nblue,caf\xe9".encode("latin-1"), 2, "not UTF-8"),
    ("missing.csv", _eufs_with(5, "blue,5.0,1.9,0.0,0.01,0.01"), 5, "expected 7 columns"),
    ("extra.csv", _eufs_with(5, "blue,5.0,1.9,0.0,0.01,0.01,0.0,9"), 5, "expected 7 columns"),
    (
        "nan.csv",
        _eufs_with(6, "blue,nan,1.9,0.0,0.01,0.01,0.0"),
        6,
        "column 'x': 'nan' is not finite",
    ),
    (
        "inf.csv",
        _eufs_with(6, "yellow,5,-inf,0.0,0.01,0.01,0.0"),
        6,
        "column 'y': '-inf' is not finite",
    ),
    (
        "var.csv",
        _eufs_with(7, "blue,5,1,0.0,x,0.01,0.0"),
        7,
        "column 'x_variance': 'x' is not a number",
    ),
    ("tag.csv", _eufs_with(4, "purple,5,1,0,0,0,0"), 4, "unknown tag 'purple'"),
    ("header.csv", _eufs_with(1, "tag,x,y,z"), 1, "EUFS header must be"),
    ("start2.csv", _eufs_with(3, "car_start,0,0,0,0,0,0"), 3, "second car_start row"),
    ("dup.csv", _eufs_with(4, "blue,5.0,1.95,0.0,0.01,0.01,0.0"), 4, "duplicate cone"),
    (
        "few.csv",
        eufs_text([("blue", 0, 1), ("blue", 5, 1), ("yellow", 0, -1)]),
        None,
        "at least 3 blue",
    ),
    (
        "fsds_start.csv",
        "car_start,0,0,0,0,0,0\n" + fsds_text(lane_rows()),
        1,
        "unknown tag 'car_start'",
    ),
    (
        "nostart.csv",
        fsds_text([r for r in lane_rows() if r[0] != "big_orange"]),
        None,
        "no start pose",
    ),
    ("list.yaml", "- 1\n- 2\n", None, "not a recognised track file"),
    ("scalar.yaml", "hello\n", None, "not a recognised track file"),
    ("syntax.yaml", "conesim_track: 1\nname: [unclosed\n", 3, "not valid YAML"),
    # PyYAML 6.0.4 stops at its nesting limit with a mark (line 1); older
    # releases hit Python's recursion limit, with no line (ANY_LINE).
    ("deep.yaml", "[" * 5000 + "]" * 5000, ANY_LINE, "YAML"),
    (
        "unknown.yaml",
        OWN_YAML + "colour: red\n",
        11,
        "unknown key 'colour'; allowed keys: cones, conesim_track",
    ),
    (
        "kind.yaml",
        OWN_YAML + "  green: [[1, 2]]\n",
        11,
        "cones: unknown key 'green'; allowed keys: big_orange, blue",
    ),
    ("missing.yaml", OWN_YAML.replace("layout: open\n", ""), None, "missing key 'layout'"),
    (
        "layout.yaml",
        OWN_YAML.replace("layout: open", "layout: oval"),
        4,
        "'oval' is not one of closed, open, skidpad",
    ),
    (
        "version.yaml",
        OWN_YAML.replace("conesim_track: 1", "conesim_track: 2"),
        1,
        "unsupported version '2'",
    ),
    (
        "pose.yaml",
        OWN_YAML.replace("[-2.0, 0.0, 0.0]", "[-2.0, 0.0]"),
        5,
        "start_pose: expected [x, y, yaw]",
    ),
    (
        "point.yaml",
        OWN_YAML.replace("[20.0, 1.9]]", "[20.0, 1.9, 3.0]]"),
        8,
        "cones.blue: expected [x, y]",
    ),
    (
        "quoted.yaml",
        OWN_YAML.replace("[5.0, 1.9]", "['5.0', 1.9]"),
        8,
        "cones.blue: '5.0' is not a number",
    ),
    ("bool.yaml", OWN_YAML.replace("[5.0, 1.9]", "[true, 1.9]"), 8, "'true' is not a number"),
    ("nan.yaml", OWN_YAML.replace("[5.0, 1.9]", "[.nan, 1.9]"), 8, "'.nan' is not finite"),
    (
        "cones.yaml",
        OWN_YAML.replace("[[5.0, 1.9], [10.0, 1.9], [15.0, 1.9], [20.0, 1.9]]", "5"),
        8,
        "expected a list of [x, y]",
    ),
    (
        "gp.yaml",
        OWN_YAML.replace("global_path: null", "global_path: nope.csv"),
        6,
        "'nope.csv' not found",
    ),
    (
        "fssim.yaml",
        FSSIM_YAML + "friction: 1.0\n",
        38,
        "unknown key 'friction'; allowed keys: cones_left",
    ),
    (
        "far.yaml",
        OWN_YAML.replace("[5.0, 1.9]", "[5.0e9, 1.9]"),
        8,
        "more than 1e+06 m from the origin",
    ),
    ("dupkey.yaml", OWN_YAML + "name: again\n", 11, "duplicate key 'name'"),
    (
        "far_start.yaml",
        OWN_YAML.replace("[-2.0, 0.0, 0.0]", "[1.0e9, 0.0, 0.0]"),
        None,
        "start pose (1e+09, 0) is more than 1e+06 m from the origin",
    ),
]


@pytest.mark.parametrize(
    ("name", "content", "line", "message"), BAD_FILES, ids=[b[0] for b in BAD_FILES]
)
def test_bad_input_raises_track_format_error(
    tmp_path: Path, name: str, content: str | bytes, line: int | None, message: str
) -> None:
    """One exception class, naming the file, the line where there is one, and the problem."""
    path = write(tmp_path, name, content)
    with pytest.raises(TrackFormatError) as info:
        read_track(path)
    text = str(info.value)
    assert text.startswith(str(path) + ":"), text
    if line == ANY_LINE:
        line = info.value.line
    assert info.value.line == line, text
    if line is not None:
        assert text.startswith(f"{path}:{line}: "), text
    assert message in text


def test_missing_file_and_directory(tmp_path: Path) -> None:
    """A path that is not a readable file is a TrackFormatError too."""
    with pytest.raises(TrackFormatError, match="no such file"):
        read_track(tmp_path / "nope.csv")
    with pytest.raises(TrackFormatError, match="directory"):
        read_track(tmp_path)


@pytest.mark.skipif(not Path("/dev/zero").exists(), reason="needs a /dev/zero device")
def test_device_file_is_refused_without_reading_it() -> None:
    """A character device (st_size 0, endless data) is refused as not a regular file."""
    with pytest.raises(TrackFormatError, match="not a regular file") as info:
        read_track(Path("/dev/zero"))
    assert str(info.value).startswith("/dev/zero: ")


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs os.mkfifo")
def test_fifo_is_refused_without_blocking(tmp_path: Path) -> None:
    """A FIFO is refused before it is opened (opening one would wait for a writer)."""
    fifo = tmp_path / "track.fifo"
    os.mkfifo(fifo)
    with pytest.raises(TrackFormatError, match="not a regular file"):
        read_track(fifo)


def test_read_stops_after_the_size_cap(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """At most MAX_FILE_BYTES + 1 bytes are read, whatever the reported size."""
    monkeypatch.setattr(readers, "MAX_FILE_BYTES", 64)
    path = write(tmp_path, "big.yaml", OWN_YAML)
    with pytest.raises(TrackFormatError, match="larger than 64 bytes") as info:
        read_track(path)
    assert info.value.path == str(path)


def test_load_track_by_name_and_path(tmp_path: Path) -> None:
    """A shipped name loads the shipped track; a path loads the file."""
    assert load_track("autocross").name == "autocross"
    path = write(tmp_path, "lane.yaml", OWN_YAML)
    assert load_track(path).name == "lane"
    assert load_track(str(path)).name == "lane"


def test_load_track_unknown_name_lists_shipped_names() -> None:
    """An unknown name says which tracks there are."""
    with pytest.raises(TrackNotFoundError) as info:
        load_track("nurburgring")
    for name in shipped_tracks():
        assert name in str(info.value)
    assert isinstance(info.value, TrackFormatError)


def test_fssim_front_wing_wins_over_cg(tmp_path: Path) -> None:
    """Both poses given: the front-wing pose (the one fssim places the car by),
    moved back to the CG, 1.515 m behind the wing tip along the heading."""
    text = FSSIM_YAML + "starting_pose_cg: [-3.0, 0.0, 0.0]\n"
    start = read_track(write(tmp_path, "a.yaml", text)).start_pose
    d = 1.515
    assert start == Pose2D(-2.0 - d * math.cos(0.087), -d * math.sin(0.087), 0.087)


def test_fssim_front_wing_offset_is_the_default_vehicle_s() -> None:
    """The reader's CG-to-front-wing distance is the default car's (``tracks``
    cannot import ``sim``, so a test keeps the two equal)."""
    from conesim.sim.vehicle_params import VehicleParams
    from conesim.tracks.readers_yaml import FSSIM_CG_TO_FRONT_WING

    p = VehicleParams()
    assert p.cg_to_front + p.front_overhang == pytest.approx(FSSIM_CG_TO_FRONT_WING, abs=1e-12)


def test_error_is_picklable() -> None:
    """Errors cross process boundaries (multiprocessing runners) intact."""
    import pickle

    err = TrackFormatError("bad", "f.csv", 3)
    back = pickle.loads(pickle.dumps(err))
    assert str(back) == "f.csv:3: bad" and back.line == 3
    assert math.isfinite(float(np.float64(1.0)))


def test_exact_repeat_is_dropped_with_a_warning(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """A cone listed twice exactly (as fssim's own files do) is one cone, with a warning."""
    text = eufs_text(lane_rows())
    lines = text.splitlines()
    repeated = lines[3]
    path = tmp_path / "repeat.csv"
    path.write_text("\n".join([*lines, repeated]) + "\n")
    original = tmp_path / "original.csv"
    original.write_text(text)
    with caplog.at_level("WARNING", logger="conesim.tracks.readers"):
        track = read_track(path)
    assert len(track.cones) == len(read_track(original).cones)
    assert f"repeat.csv:{len(lines) + 1}" in caplog.text and "dropped" in caplog.text
