"""GPS <-> local Cartesian conversion for the `reference` frame.

Two projections, both vectorised over numpy arrays:

* The ROS pipeline's equirectangular projection (``gps_to_local_cartesian``), exactly as
  the ROS pipeline's ``gps_to_local_cartesian_node`` computes it, with R = 6378137 m::

      x = (lon_r - ref_lon_r) * cos(ref_lat_r) * R
      y = (lat_r - ref_lat_r) * R
      z = 0

  and its exact algebraic inverse (``local_cartesian_to_gps``), which the
  simulator uses to generate fixes so that truth and estimate agree. One
  departure from the ROS pipeline: a longitude difference beyond +-180 deg (a track
  across the antimeridian) is taken the short way round, and the inverse's
  longitude is wrapped into [-180, 180] (the ROS pipeline's formula put a fix 21 m
  east of such an origin 38,000 km west); everywhere else the numbers are
  the ROS pipeline's bit for bit.

* Exact WGS84 geodetic -> ECEF -> ENU (``geodetic_to_enu`` / ``enu_to_geodetic``),
  through pymap3d (a well-kept library; no reason to hand-write the ellipsoid
  maths). Use it far from the origin: at latitude 37.5 deg the ROS pipeline's sphere
  makes northing 0.300 % too large and easting 0.124 % too small (0.30 / 0.12 m
  at 100 m; REFERENCES.md, "Geodesy").

The module is a dependency-free leaf (numpy, pymap3d): the simulator's GPS
receiver model imports it too.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pymap3d
from numpy.typing import ArrayLike, NDArray

R_EARTH = 6378137.0  # [m] the ROS pipeline's R_EARTH (WGS84 equatorial radius)

FloatArray = NDArray[np.float64]


class GeodesyError(ValueError):
    """A latitude, longitude or origin that cannot be converted."""


def _check_lat_lon(lat: FloatArray, lon: FloatArray, where: str) -> None:
    if lat.shape != lon.shape:
        raise GeodesyError(
            f"{where}: latitude and longitude must have one shape, got {lat.shape} and {lon.shape}"
        )
    if not (np.all(np.isfinite(lat)) and np.all(np.isfinite(lon))):
        raise GeodesyError(f"{where}: latitude/longitude must be finite (got NaN or inf)")
    for name, values, limit in (("latitude", lat, 90.0), ("longitude", lon, 180.0)):
        bad = np.abs(values) > limit
        if np.any(bad):
            first = float(np.asarray(values)[bad].flat[0])
            raise GeodesyError(
                f"{where}: {name} out of range [-{limit:g}, {limit:g}] deg: {first:g}"
            )


@dataclass(frozen=True, slots=True)
class ReferenceOrigin:
    """The geodetic origin of the `reference` frame (ENU).

    Attributes:
        lat_deg: latitude [deg], in [-90, 90] (the ROS pipeline's launch default 37.540190).
        lon_deg: longitude [deg], in [-180, 180] (the ROS pipeline's default 127.076488).
        alt_m: ellipsoidal height [m]; only the exact WGS84 conversion uses it.
    """

    lat_deg: float = 37.540190
    lon_deg: float = 127.076488
    alt_m: float = 0.0

    def __post_init__(self) -> None:
        _check_lat_lon(np.asarray(self.lat_deg), np.asarray(self.lon_deg), "ReferenceOrigin")
        if not math.isfinite(self.alt_m):
            raise GeodesyError(f"ReferenceOrigin.alt_m must be finite, got {self.alt_m!r}")
        if abs(self.lat_deg) >= 89.9:
            raise GeodesyError(
                f"ReferenceOrigin.lat_deg={self.lat_deg}: the equirectangular projection "
                "is singular at the poles; allowed range is (-89.9, 89.9) deg"
            )


DEFAULT_ORIGIN = ReferenceOrigin()


def gps_to_local_cartesian(
    lat_deg: ArrayLike, lon_deg: ArrayLike, origin: ReferenceOrigin = DEFAULT_ORIGIN
) -> tuple[FloatArray, FloatArray]:
    """The ROS pipeline's projection: geodetic -> (x east, y north) in `reference`.

    Args:
        lat_deg: latitude(s) [deg], any shape.
        lon_deg: longitude(s) [deg], same shape.
        origin: the `reference` origin.

    Returns:
        (x, y) [m], arrays of the input shape. z is 0 by the ROS pipeline's definition.

    Raises:
        GeodesyError: NaN/inf or out-of-range latitude or longitude.
    """
    lat = np.asarray(lat_deg, dtype=float)
    lon = np.asarray(lon_deg, dtype=float)
    _check_lat_lon(lat, lon, "gps_to_local_cartesian")
    lat_r, lon_r = np.radians(lat), np.radians(lon)
    ref_lat_r, ref_lon_r = math.radians(origin.lat_deg), math.radians(origin.lon_deg)
    x = _wrapped(lon_r - ref_lon_r, math.pi) * math.cos(ref_lat_r) * R_EARTH
    y = (lat_r - ref_lat_r) * R_EARTH
    return x, y


def _wrapped(values: FloatArray, half: float) -> FloatArray:
    """``values`` moved into [-half, half] by a whole turn where they lie
    beyond it (across the antimeridian), unchanged bit for bit elsewhere."""
    turn = 2.0 * half
    out: FloatArray = np.where(
        values > half, values - turn, np.where(values < -half, values + turn, values)
    )
    return out[()]  # a 0-d result as a numpy scalar, as the other coordinate


def wrapped_lon_difference(d_lon_r: float) -> float:
    """One longitude difference [rad] as :func:`gps_to_local_cartesian` takes
    it (``_wrapped`` on a float): the short way round across the antimeridian."""
    if d_lon_r > math.pi:
        return d_lon_r - 2.0 * math.pi
    if d_lon_r < -math.pi:
        return d_lon_r + 2.0 * math.pi
    return d_lon_r


def local_cartesian_to_gps(
    x: ArrayLike, y: ArrayLike, origin: ReferenceOrigin = DEFAULT_ORIGIN
) -> tuple[FloatArray, FloatArray]:
    """Exact inverse of :func:`gps_to_local_cartesian`.

    Args:
        x: east [m] in `reference`, any shape.
        y: north [m], same shape.
        origin: the `reference` origin.

    Returns:
        (lat, lon) [deg].

    Raises:
        GeodesyError: NaN/inf input, or a point that maps beyond the poles.
    """
    xa = np.asarray(x, dtype=float)
    ya = np.asarray(y, dtype=float)
    if xa.shape != ya.shape:
        raise GeodesyError(
            f"local_cartesian_to_gps: x and y must have one shape, got {xa.shape} and {ya.shape}"
        )
    if not (np.all(np.isfinite(xa)) and np.all(np.isfinite(ya))):
        raise GeodesyError("local_cartesian_to_gps: x/y must be finite (got NaN or inf)")
    ref_lat_r, ref_lon_r = math.radians(origin.lat_deg), math.radians(origin.lon_deg)
    lat = np.degrees(ya / R_EARTH + ref_lat_r)
    lon = _wrapped(np.degrees(xa / (R_EARTH * math.cos(ref_lat_r)) + ref_lon_r), 180.0)
    _check_lat_lon(lat, lon, "local_cartesian_to_gps")
    return lat, lon


def geodetic_to_enu(
    lat_deg: ArrayLike,
    lon_deg: ArrayLike,
    alt_m: ArrayLike = 0.0,
    origin: ReferenceOrigin = DEFAULT_ORIGIN,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Exact WGS84 geodetic -> ECEF -> ENU about ``origin`` (pymap3d).

    Returns:
        (east, north, up) [m].
    """
    lat = np.asarray(lat_deg, dtype=float)
    lon = np.asarray(lon_deg, dtype=float)
    _check_lat_lon(lat, lon, "geodetic_to_enu")
    e, n, u = pymap3d.geodetic2enu(
        lat, lon, np.asarray(alt_m, dtype=float), origin.lat_deg, origin.lon_deg, origin.alt_m
    )
    return np.asarray(e, dtype=float), np.asarray(n, dtype=float), np.asarray(u, dtype=float)


def enu_to_geodetic(
    east: ArrayLike,
    north: ArrayLike,
    up: ArrayLike = 0.0,
    origin: ReferenceOrigin = DEFAULT_ORIGIN,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Exact WGS84 ENU about ``origin`` -> geodetic (pymap3d).

    Returns:
        (lat [deg], lon [deg], alt [m]).
    """
    e = np.asarray(east, dtype=float)
    n = np.asarray(north, dtype=float)
    u = np.asarray(up, dtype=float)
    if not (np.all(np.isfinite(e)) and np.all(np.isfinite(n)) and np.all(np.isfinite(u))):
        raise GeodesyError("enu_to_geodetic: east/north/up must be finite (got NaN or inf)")
    lat, lon, alt = pymap3d.enu2geodetic(e, n, u, origin.lat_deg, origin.lon_deg, origin.alt_m)
    return np.asarray(lat, dtype=float), np.asarray(lon, dtype=float), np.asarray(alt, dtype=float)
