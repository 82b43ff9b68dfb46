"""The global path: the ROS pipeline's ``lat,lon,cov`` CSV, loaded into `reference`.

The ROS pipeline's ``status_colored_path_publisher`` reads one ``lat,lon,cov`` per line,
projects each point with the same reference origin as ``gps_to_local_cartesian``
and colours each point red where ``cov`` exceeds a threshold (0.0025 m^2, i.e. a
5 cm standard deviation) and green otherwise. This module is that node's data
half: reader, writer, status, and a path derived from a track's centreline for
tracks that ship without one.
"""

from __future__ import annotations

import math
import os
import uuid
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

from conesim.core.geodesy import (
    DEFAULT_ORIGIN,
    ReferenceOrigin,
    gps_to_local_cartesian,
    local_cartesian_to_gps,
)
from conesim.core.polyline import Polyline
from conesim.tracks.errors import TrackFormatError
from conesim.tracks.model import Track

COV_THRESHOLD_M2 = 0.0025  # [m^2] seed: "error > threshold, e.g. >5 cm if threshold=0.0025"
DERIVED_PATH_COV_M2 = 0.0004  # [m^2] a path surveyed from the cones: 2 cm sigma
MIN_POINTS = 2  # a path needs at least one segment

FloatArray = NDArray[np.float64]


class GlobalPathError(ValueError):
    """A malformed global path file or array; the message names file and line."""


@dataclass(frozen=True)
class GlobalPath:
    """A global path in `reference` with its per-point covariance.

    Attributes:
        xy: (n, 2) points in `reference` [m], in driving order.
        cov: (n,) position covariance of each point [m^2].
        lat: (n,) latitude [deg] of each point, as read or written.
        lon: (n,) longitude [deg].
        origin: the `reference` origin the points were projected with.
        closed: True when the last point joins back to the first (a loop).
        cov_threshold: the ROS pipeline's red/green threshold [m^2].
    """

    xy: FloatArray
    cov: FloatArray
    lat: FloatArray
    lon: FloatArray
    origin: ReferenceOrigin = DEFAULT_ORIGIN
    closed: bool = False
    cov_threshold: float = COV_THRESHOLD_M2

    def __post_init__(self) -> None:
        # Own read-only copies: the caller's arrays stay as they were.
        for name in ("xy", "cov", "lat", "lon"):
            array = np.array(getattr(self, name), dtype=float)
            array.setflags(write=False)
            object.__setattr__(self, name, array)
        n = len(self.xy)
        shapes = (self.xy.shape, self.cov.shape, self.lat.shape, self.lon.shape)
        if shapes != ((n, 2), (n,), (n,), (n,)):
            raise GlobalPathError(
                "GlobalPath: xy must be (n, 2) and cov, lat and lon (n,), got "
                + ", ".join(str(shape) for shape in shapes)
            )
        if n < MIN_POINTS:
            raise GlobalPathError(f"GlobalPath: needs at least {MIN_POINTS} points, got {n}")
        for name in ("xy", "cov", "lat", "lon"):
            bad = np.flatnonzero(~np.isfinite(getattr(self, name)).reshape(n, -1).all(axis=1))
            if len(bad):
                raise GlobalPathError(f"GlobalPath: {name} of point {bad[0]} is not finite")
        if np.any(self.cov < 0.0):
            raise GlobalPathError(
                f"GlobalPath: cov of point {int(np.argmax(self.cov < 0.0))} is negative"
            )
        step = np.hypot(*np.diff(self.xy, axis=0).T)
        if np.any(step == 0.0):
            k = int(np.argmax(step == 0.0)) + 1
            raise GlobalPathError(f"GlobalPath: point {k} repeats the one before it")

    @property
    def high_covariance(self) -> NDArray[np.bool_]:
        """(n,) True where the ROS pipeline draws the point red (cov > threshold)."""
        return self.cov > self.cov_threshold

    @property
    def status(self) -> list[str]:
        """(n,) the ROS pipeline's colour per point: ``"red"`` or ``"green"``."""
        return ["red" if high else "green" for high in self.high_covariance]

    @cached_property
    def polyline(self) -> Polyline:
        """The path's points as a polyline (a closed path's includes the
        segment from the last point back to the first)."""
        return Polyline(self.xy, self.closed)


def global_path_from_geodetic(
    lat: ArrayLike,
    lon: ArrayLike,
    cov: ArrayLike,
    origin: ReferenceOrigin = DEFAULT_ORIGIN,
    closed: bool | None = None,
) -> GlobalPath:
    """Build a path from geodetic points, projected with the ROS pipeline's formula.

    Args:
        lat: (n,) [deg].
        lon: (n,) [deg].
        cov: (n,) [m^2], non-negative.
        origin: the `reference` origin.
        closed: whether the path is a loop; None decides from the geometry (the
            last point lies within two median segment lengths of the first).
    """
    lat_a = np.asarray(lat, dtype=float).reshape(-1)
    lon_a = np.asarray(lon, dtype=float).reshape(-1)
    cov_a = np.asarray(cov, dtype=float).reshape(-1)
    if not (len(lat_a) == len(lon_a) == len(cov_a)):
        raise GlobalPathError("global path: lat, lon and cov must have the same length")
    if not np.all(np.isfinite(cov_a)) or np.any(cov_a < 0):
        raise GlobalPathError("global path: cov must be finite and >= 0")
    x, y = gps_to_local_cartesian(lat_a, lon_a, origin)
    xy = np.column_stack([x, y])
    if closed is None:
        closed = _looks_closed(xy)
    return GlobalPath(xy=xy, cov=cov_a, lat=lat_a, lon=lon_a, origin=origin, closed=closed)


def global_path_from_centreline(
    xy: ArrayLike,
    closed: bool,
    origin: ReferenceOrigin = DEFAULT_ORIGIN,
    cov: ArrayLike | float = DERIVED_PATH_COV_M2,
) -> GlobalPath:
    """Georeference a centreline in `reference` as a global path.

    For tracks that come without a global path: the points are mapped to
    lat/lon with the exact inverse of the ROS pipeline's projection, so reading the
    written CSV back reproduces ``xy`` to ~1e-9 m.

    Args:
        xy: (n, 2) centreline points in `reference` [m], in driving order.
        closed: whether the centreline is a loop.
        origin: the `reference` origin.
        cov: per-point covariance [m^2], scalar or (n,).
    """
    pts = np.asarray(xy, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 2:
        raise GlobalPathError(f"global path: the centreline must be (n, 2) [m], got {pts.shape}")
    cov_a = np.broadcast_to(np.asarray(cov, dtype=float), (len(pts),)).copy()
    lat, lon = local_cartesian_to_gps(pts[:, 0], pts[:, 1], origin)
    return global_path_from_geodetic(lat, lon, cov_a, origin, closed=closed)


def _looks_closed(xy: FloatArray) -> bool:
    if len(xy) < 4:
        return False
    step = float(np.median(np.hypot(*np.diff(xy, axis=0).T)))
    return bool(np.hypot(*(xy[-1] - xy[0])) <= 2.0 * step)


def read_global_path_csv(
    path: str | os.PathLike[str],
    origin: ReferenceOrigin = DEFAULT_ORIGIN,
    closed: bool | None = None,
) -> GlobalPath:
    """Read the ROS pipeline's global path CSV: one ``lat,lon,cov`` per line.

    A first line ``lat,lon,cov`` is accepted as a header; blank lines are skipped.

    Raises:
        GlobalPathError: naming the file and line: unreadable or binary file,
            wrong column count, non-numeric or non-finite field, latitude or
            longitude out of range, negative covariance, a point repeated from
            the one before it, or fewer than two points.
    """
    p = Path(path)
    try:
        raw = p.read_bytes()
    except OSError as exc:
        raise GlobalPathError(f"{p}: cannot read global path: {exc.strerror}") from None
    if b"\x00" in raw:
        raise GlobalPathError(f"{p}: binary file, expected text lines 'lat,lon,cov'")
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise GlobalPathError(f"{p}: not UTF-8 text, expected lines 'lat,lon,cov'") from None
    rows: list[tuple[float, float, float]] = []
    for lineno, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if not stripped or (lineno == 1 and stripped.replace(" ", "").lower() == "lat,lon,cov"):
            continue
        rows.append(_parse_row(stripped, p, lineno, rows))
    if len(rows) < MIN_POINTS:
        raise GlobalPathError(
            f"{p}: a global path needs at least {MIN_POINTS} points, found {len(rows)}"
        )
    lat, lon, cov = (np.array(col) for col in zip(*rows, strict=True))
    return global_path_from_geodetic(lat, lon, cov, origin, closed=closed)


def _parse_row(
    line: str, path: Path, lineno: int, previous: list[tuple[float, float, float]]
) -> tuple[float, float, float]:
    fields = [f.strip() for f in line.split(",")]
    where = f"{path}:{lineno}"
    if len(fields) != 3:
        raise GlobalPathError(f"{where}: expected 3 columns 'lat,lon,cov', found {len(fields)}")
    values = []
    for name, field in zip(("lat", "lon", "cov"), fields, strict=True):
        try:
            value = float(field)
        except ValueError:
            raise GlobalPathError(f"{where}: column '{name}': {field!r} is not a number") from None
        if not math.isfinite(value):
            raise GlobalPathError(f"{where}: column '{name}': {field!r} is not finite")
        values.append(value)
    lat, lon, cov = values
    if abs(lat) > 90.0:
        raise GlobalPathError(f"{where}: column 'lat': {lat} is outside [-90, 90] deg")
    if abs(lon) > 180.0:
        raise GlobalPathError(f"{where}: column 'lon': {lon} is outside [-180, 180] deg")
    if cov < 0.0:
        raise GlobalPathError(f"{where}: column 'cov': {cov} is negative")
    if previous and previous[-1][:2] == (lat, lon):
        raise GlobalPathError(f"{where}: point repeats the one on the line before it")
    return lat, lon, cov


def write_global_path_csv(path: str | os.PathLike[str], global_path: GlobalPath) -> None:
    """Write ``global_path`` as the ROS pipeline's CSV (no header), atomically.

    The file appears complete or not at all (temporary file + ``os.replace``).
    Latitude and longitude are written with 12 decimals (~1e-7 m).
    """
    lines = [
        f"{lat:.12f},{lon:.12f},{cov:.6g}\n"
        for lat, lon, cov in zip(global_path.lat, global_path.lon, global_path.cov, strict=True)
    ]
    atomic_write_text(Path(path), "".join(lines))


def atomic_write_text(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` through a temporary file and ``os.replace``.

    The temporary file is created with ``open(..., "x")``, so it gets the
    ordinary permissions (0666 less the umask), unlike ``mkstemp``'s 0600.
    """
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.{uuid.uuid4().hex}.tmp")
    try:
        with open(tmp, "x", encoding="utf-8") as handle:
            handle.write(text)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def global_path_for_track(track: Track, origin: ReferenceOrigin = DEFAULT_ORIGIN) -> GlobalPath:
    """The global path that goes with ``track``.

    The track's own ``lat,lon,cov`` CSV when it has one; otherwise its true
    centreline, georeferenced at ``origin`` (the issue's rule for tracks that
    come without a global path, e.g. fssim, EUFS and FSDS files).
    """
    closed = track.layout == "closed"
    if track.global_path_file is not None:
        return read_global_path_csv(track.global_path_file, origin, closed=closed)
    return global_path_from_centreline(track.centreline, closed=closed, origin=origin)


OFF_TRACK_MARGIN_M = 1.0  # [m] beyond half the track's widest width
FIT_FRACTION = 0.1  # more than this share off (or uncovered) is an error
DENSE_SPACING_M = 0.25  # [m] the polylines' spacing for the nearest-point queries


def global_path_findings(track: Track, path: GlobalPath) -> tuple[list[str], list[str]]:
    """(warnings, errors) of a global path against its track's centreline.

    A point of the path is off the track when it lies farther from the
    centreline than half the track's widest width plus ``OFF_TRACK_MARGIN_M``
    (a surveyed line may run anywhere between the boundaries); a centreline
    point is uncovered when the path is that far from it. Some points off
    (a bad fix) is a warning; more than ``FIT_FRACTION`` of them off, or of
    the centreline uncovered, is an error: the car would follow, classify
    its cones by and take its speeds from a path that is not this track's
    (a wrong origin, another track's file).

    A track whose geometry cannot be derived gives no findings here (the
    track validator reports it).
    """
    try:
        centre = np.asarray(track.centreline, dtype=float)
        limit = 0.5 * float(np.max(track.widths)) + OFF_TRACK_MARGIN_M
    except TrackFormatError:
        return [], []
    path_name = "global path"
    if track.global_path_file is not None:
        path_name = f"global path {track.global_path_file.name}"
    fine = DENSE_SPACING_M
    dense_centre = Polyline(centre, track.layout == "closed").resample(fine).points
    off_d, _ = cKDTree(dense_centre).query(path.xy)
    covered, _ = cKDTree(path.polyline.resample(fine).points).query(centre)
    warnings: list[str] = []
    errors: list[str] = []
    off = off_d > limit
    if off.any():
        i = int(np.argmax(off_d))
        x, y = path.xy[i]
        text = (
            f"{path_name}: {int(off.sum())} of {len(off)} points lie more than {limit:.1f} m "
            f"from the track's centreline (up to {off_d[i]:.1f} m, at ({x:.1f}, {y:.1f}))"
        )
        (errors if off.mean() > FIT_FRACTION else warnings).append(text)
    uncovered = covered > limit
    if uncovered.mean() > FIT_FRACTION:
        errors.append(
            f"{path_name} does not follow the track: {100.0 * uncovered.mean():.0f} % of its "
            f"centreline is more than {limit:.1f} m from the path"
        )
    return warnings, errors
