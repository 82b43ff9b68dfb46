"""Reading a track file of any supported format, recognised by its content.

Formats (see readers_yaml.py and readers_csv.py): our own YAML
(``conesim_track: 1``), fssim YAML (``cones_left``, ...), EUFS CSV (header
``tag,x,y,...``) and FSDS CSV (the same columns, no header). The extension
does not matter: an EUFS file named ``.txt`` is read as EUFS.

After parsing, every format goes through the same checks (``assemble``):
cones and start pose within ``MAX_COORDINATE`` of the origin, no two cones
closer than 0.1 m (cones are 0.23 m wide, so such a pair is a duplicate), at
least 3 blue and 3 yellow cones, a layout (detected when the format does not
state it), a start pose (derived from the big orange cones when the file has
none) and a derivable geometry. Every problem raises
`TrackFormatError` naming the file and, where there is one, the line.
"""

from __future__ import annotations

import logging
import os
import stat
from enum import StrEnum
from pathlib import Path

import numpy as np
import yaml
from scipy.spatial import cKDTree

from conesim.tracks import readers_csv, readers_yaml
from conesim.tracks.errors import TrackFormatError
from conesim.tracks.geometry import derive_start_pose, detect_layout
from conesim.tracks.kinds import ConeKind
from conesim.tracks.lanes import MIN_SIDE_CONES
from conesim.tracks.model import MAX_COORDINATE, Track
from conesim.tracks.rawtrack import RawTrack
from conesim.tracks.yamlnodes import compose, mapping

MAX_FILE_BYTES = 20_000_000  # a track file is kilobytes; anything this large is not one
_log = logging.getLogger(__name__)
DUPLICATE_RADIUS = 0.1  # [m] two cones closer than this are one cone listed twice


class TrackFileFormat(StrEnum):
    """The track file formats this package reads."""

    CONESIM = "conesim"
    FSSIM = "fssim"
    EUFS = "eufs"
    FSDS = "fsds"


def read_track(path: str | os.PathLike[str]) -> Track:
    """Read a track file in any supported format.

    Args:
        path: the file.

    Returns:
        The track, with its geometry already derived (so a track that loads
        can be driven on and measured).

    Raises:
        TrackFormatError: the file cannot be read or is not a valid track; the
            message names the file, the line where there is one, and the problem.
    """
    file = Path(path)
    text = read_text(file)
    _, raw = parse(text, file)
    return assemble(raw, file)


def read_text(path: Path) -> str:
    """The file's text, refusing missing, empty, huge, binary and non-UTF-8 files.

    Only a regular file is read (a device such as ``/dev/zero`` or a FIFO is
    refused before it is opened), and at most ``MAX_FILE_BYTES + 1`` bytes
    are read whatever the file system reports as its size.
    """
    try:
        if not stat.S_ISREG(path.stat().st_mode):
            if path.is_dir():
                raise TrackFormatError("is a directory, not a track file", path)
            raise TrackFormatError("not a regular file (a device, FIFO or socket?)", path)
        with path.open("rb") as file:
            data = file.read(MAX_FILE_BYTES + 1)
    except FileNotFoundError:
        raise TrackFormatError("no such file", path) from None
    except IsADirectoryError:
        raise TrackFormatError("is a directory, not a track file", path) from None
    except OSError as exc:
        raise TrackFormatError(f"cannot read: {exc.strerror or exc}", path) from None
    if len(data) > MAX_FILE_BYTES:
        raise TrackFormatError(f"file is larger than {MAX_FILE_BYTES} bytes", path)
    if not data.strip():
        raise TrackFormatError("empty file", path)
    if b"\x00" in data:
        raise TrackFormatError("binary file, expected a text track file", path)
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data[: exc.start].count(b"\n") + 1
        raise TrackFormatError("not UTF-8 text (a binary file?)", path, line) from None


def detect_format(text: str, path: Path) -> TrackFileFormat:
    """Recognise the format of a track file by its content."""
    return parse(text, path)[0]


def parse(text: str, path: Path) -> tuple[TrackFileFormat, RawTrack]:
    """Recognise the format and parse the file's content."""
    first = next((line for line in text.splitlines() if line.strip()), "")
    csv_kind = readers_csv.looks_like_csv(first)
    if csv_kind == "eufs":
        return TrackFileFormat.EUFS, readers_csv.read_eufs_csv(text, path)
    if csv_kind == "fsds":
        return TrackFileFormat.FSDS, readers_csv.read_fsds_csv(text, path)
    root = compose(text, path)
    if isinstance(root, yaml.MappingNode):
        entries = mapping(root, path, "track")
        if "conesim_track" in entries:
            return TrackFileFormat.CONESIM, readers_yaml.read_conesim_yaml(root, path)
        if readers_yaml.is_fssim(entries):
            return TrackFileFormat.FSSIM, readers_yaml.read_fssim_yaml(root, path)
    raise TrackFormatError(
        "not a recognised track file: expected conesim YAML ('conesim_track: 1'), fssim YAML "
        "('cones_left', 'cones_right', ...), EUFS CSV (header "
        f"'{readers_csv.EUFS_HEADER}') or FSDS CSV (rows 'blue,x,y,...')",
        path,
    )


def assemble(raw: RawTrack, path: Path) -> Track:
    """Check a parsed file's cones and build its `Track` (see the module docstring)."""
    _drop_exact_repeats(raw, path)
    _check_cones(raw, path)
    _check_start_pose(raw, path)
    cones = np.array([[c.x, c.y] for c in raw.cones], dtype=float).reshape(-1, 2)
    kinds = tuple(c.kind for c in raw.cones)
    try:
        layout = raw.layout if raw.layout is not None else detect_layout(cones, kinds)
        start = raw.start_pose
        if start is None:
            start = derive_start_pose(cones, kinds, layout)
        track = Track(
            name=raw.name or path.stem,
            cones=cones,
            kinds=kinds,
            start_pose=start,
            layout=layout,
            source=path,
            global_path_file=raw.global_path_file,
            description=raw.description,
        )
        _ = track.geometry  # derive now: a track that loads is a track that works
    except TrackFormatError as exc:
        raise exc.with_path(path) from None
    return track


def _drop_exact_repeats(raw: RawTrack, path: Path) -> None:
    """Drop a cone listed twice with the same kind and position, with a warning.

    Published files do this (fssim's own acceleration.yaml and skidpad.yaml each
    list one orange cone twice); it is one cone, not a malformed file. Two cones
    merely close together, or of different kinds, are still refused by
    ``_check_cones``.
    """
    seen: dict[tuple[ConeKind, float, float], int] = {}
    kept = []
    for cone in raw.cones:
        key = (cone.kind, cone.x, cone.y)
        if key in seen:
            _log.warning(
                "%s:%d: %s cone at (%g, %g) repeats line %d exactly; dropped",
                path, cone.line, cone.kind, cone.x, cone.y, seen[key],
            )  # fmt: skip
            continue
        seen[key] = cone.line
        kept.append(cone)
    raw.cones = kept


def _check_cones(raw: RawTrack, path: Path) -> None:
    for cone in raw.cones:
        if max(abs(cone.x), abs(cone.y)) > MAX_COORDINATE:
            raise TrackFormatError(
                f"cone at ({cone.x:g}, {cone.y:g}) is more than {MAX_COORDINATE:g} m "
                "from the origin",
                path,
                cone.line,
            )
    for kind in (ConeKind.BLUE, ConeKind.YELLOW):
        found = sum(1 for c in raw.cones if c.kind == kind)
        if found < MIN_SIDE_CONES:
            raise TrackFormatError(
                f"a track needs at least {MIN_SIDE_CONES} {kind} cones, found {found}", path
            )
    xy = np.array([[c.x, c.y] for c in raw.cones])
    pairs = sorted(cKDTree(xy).query_pairs(DUPLICATE_RADIUS))
    if pairs:
        i, j = pairs[0]
        a, b = raw.cones[i], raw.cones[j]
        gap = float(np.hypot(a.x - b.x, a.y - b.y))
        raise TrackFormatError(
            f"duplicate cone: {b.kind} cone at ({b.x:g}, {b.y:g}) is {gap:.3f} m from the "
            f"{a.kind} cone on line {a.line} (closer than {DUPLICATE_RADIUS} m)",
            path,
            b.line,
        )


def _check_start_pose(raw: RawTrack, path: Path) -> None:
    """A start pose as far out as a bad cone is a units or data error too."""
    pose = raw.start_pose
    if pose is not None and max(abs(pose.x), abs(pose.y)) > MAX_COORDINATE:
        raise TrackFormatError(
            f"start pose ({pose.x:g}, {pose.y:g}) is more than {MAX_COORDINATE:g} m from "
            "the origin",
            path,
        )
