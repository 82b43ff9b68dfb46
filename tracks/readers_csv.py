"""Readers for the CSV track formats: EUFS and FSDS.

Both have seven columns ``tag,x,y,direction,x_variance,y_variance,xy_covariance``
(REFERENCES.md, "Track file formats"); positions in metres, ``direction`` in
radians.

* EUFS: the header line above; tags blue, yellow, orange, big_orange, unknown
  and car_start (its ``direction`` is the start yaw); ``midpoint`` rows, which
  some files add, are ignored.
* FSDS: no header; tags blue, yellow, orange, big_orange; the variance
  columns are unused. FSDS files carry no start pose.

Every field must be present and numeric (the variance columns too), so that
a shifted or truncated row is caught where it is, not silently misread.
"""

from __future__ import annotations

import math
from pathlib import Path

from conesim.core.pose import Pose2D
from conesim.tracks.errors import TrackFormatError
from conesim.tracks.kinds import ConeKind
from conesim.tracks.rawtrack import RawCone, RawTrack

COLUMNS = ("tag", "x", "y", "direction", "x_variance", "y_variance", "xy_covariance")
EUFS_HEADER = ",".join(COLUMNS)
CONE_TAGS = {str(k): k for k in ConeKind}
EUFS_TAGS = set(CONE_TAGS) | {"car_start", "midpoint"}
FSDS_TAGS = {"blue", "yellow", "orange", "big_orange"}


def read_eufs_csv(text: str, path: Path) -> RawTrack:
    """Parse an EUFS track CSV (header line, then one row per cone)."""
    rows = _rows(text)
    if not rows:
        raise TrackFormatError("empty file", path)
    header_line, header = rows[0]
    if header.replace(" ", "").lower() != EUFS_HEADER:
        raise TrackFormatError(
            f"EUFS header must be {EUFS_HEADER!r}, found {header!r}", path, header_line
        )
    return _parse(rows[1:], path, EUFS_TAGS, "EUFS")


def read_fsds_csv(text: str, path: Path) -> RawTrack:
    """Parse an FSDS track CSV (no header, one row per cone)."""
    return _parse(_rows(text), path, FSDS_TAGS, "FSDS")


def looks_like_csv(first_line: str) -> str | None:
    """``"eufs"`` or ``"fsds"`` if the file's first non-blank line says so, else None."""
    flat = first_line.replace(" ", "").lower()
    if flat.startswith("tag,"):
        return "eufs"
    if "," in flat and flat.split(",", 1)[0] in EUFS_TAGS | FSDS_TAGS:
        return "fsds"
    return None


def _rows(text: str) -> list[tuple[int, str]]:
    return [(n, line.strip()) for n, line in enumerate(text.splitlines(), start=1) if line.strip()]


def _parse(rows: list[tuple[int, str]], path: Path, tags: set[str], fmt: str) -> RawTrack:
    raw = RawTrack()
    start_line = None
    for line_no, line in rows:
        fields = [f.strip() for f in line.split(",")]
        if len(fields) != len(COLUMNS):
            raise TrackFormatError(
                f"expected {len(COLUMNS)} columns ({EUFS_HEADER}), found {len(fields)}",
                path,
                line_no,
            )
        tag = fields[0].lower()
        if tag not in tags:
            raise TrackFormatError(
                f"column 'tag': unknown tag {fields[0]!r}; "
                f"{fmt} tags are: {', '.join(sorted(tags))}",
                path,
                line_no,
            )
        x, y, direction, *_ = (
            _number(field, name, path, line_no)
            for name, field in zip(COLUMNS[1:], fields[1:], strict=True)
        )
        if tag == "car_start":
            if start_line is not None:
                raise TrackFormatError(
                    f"second car_start row (the first is on line {start_line})", path, line_no
                )
            start_line = line_no
            raw.start_pose = Pose2D(x, y, direction)
        elif tag != "midpoint":
            raw.cones.append(RawCone(x, y, CONE_TAGS[tag], line_no))
    return raw


def _number(field: str, column: str, path: Path, line: int) -> float:
    try:
        value = float(field)
    except ValueError:
        raise TrackFormatError(
            f"column '{column}': {field!r} is not a number", path, line
        ) from None
    if not math.isfinite(value):
        raise TrackFormatError(f"column '{column}': {field!r} is not finite", path, line)
    return value
