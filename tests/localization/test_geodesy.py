"""Tests for localization.geodesy: the ROS pipeline's projection, its inverse, WGS84 ENU."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from conesim.core.geodesy import (
    DEFAULT_ORIGIN,
    R_EARTH,
    GeodesyError,
    ReferenceOrigin,
    enu_to_geodetic,
    geodetic_to_enu,
    gps_to_local_cartesian,
    local_cartesian_to_gps,
)


def seed_formula(lat: float, lon: float, ref_lat: float, ref_lon: float) -> tuple[float, float]:
    """The ROS pipeline's C++ lines, transcribed with math (not numpy)."""
    lat_r, lon_r = math.radians(lat), math.radians(lon)
    ref_lat_r, ref_lon_r = math.radians(ref_lat), math.radians(ref_lon)
    x = (lon_r - ref_lon_r) * math.cos(ref_lat_r) * 6378137.0
    y = (lat_r - ref_lat_r) * 6378137.0
    return x, y


def test_default_origin_is_the_seeds_launch_default() -> None:
    """The reference origin defaults to 37.540190, 127.076488."""
    assert DEFAULT_ORIGIN.lat_deg == 37.540190
    assert DEFAULT_ORIGIN.lon_deg == 127.076488
    assert R_EARTH == 6378137.0


def test_projection_matches_seed_formula_to_1e9_m() -> None:
    """Vectorised projection equals the ROS pipeline's scalar formula to 1e-9 m."""
    rng = np.random.default_rng(0)
    lat = DEFAULT_ORIGIN.lat_deg + rng.uniform(-0.01, 0.01, 200)
    lon = DEFAULT_ORIGIN.lon_deg + rng.uniform(-0.01, 0.01, 200)
    x, y = gps_to_local_cartesian(lat, lon)
    expected = np.array(
        [
            seed_formula(a, b, DEFAULT_ORIGIN.lat_deg, DEFAULT_ORIGIN.lon_deg)
            for a, b in zip(lat, lon, strict=True)
        ]
    )
    assert_allclose(x, expected[:, 0], rtol=0, atol=1e-9)
    assert_allclose(y, expected[:, 1], rtol=0, atol=1e-9)


def test_one_arcsecond_north_is_30_9_m() -> None:
    """1/3600 deg of latitude is R * pi / 648000 = 30.9220 m north."""
    x, y = gps_to_local_cartesian(DEFAULT_ORIGIN.lat_deg + 1 / 3600, DEFAULT_ORIGIN.lon_deg)
    assert_allclose(float(x), 0.0, atol=1e-12)
    assert_allclose(float(y), R_EARTH * math.pi / 648000, atol=1e-9)


def test_round_trip_below_1e6_m() -> None:
    """local -> gps -> local round-trips to < 1e-6 m over a 2 km square."""
    rng = np.random.default_rng(0)
    x = rng.uniform(-1000, 1000, 1000)
    y = rng.uniform(-1000, 1000, 1000)
    lat, lon = local_cartesian_to_gps(x, y)
    x2, y2 = gps_to_local_cartesian(lat, lon)
    assert np.max(np.hypot(x2 - x, y2 - y)) < 1e-6


@given(
    st.floats(-60, 60),
    st.floats(-170, 170),
    st.floats(-5000, 5000),
    st.floats(-5000, 5000),
)
def test_round_trip_any_origin(lat0: float, lon0: float, x: float, y: float) -> None:
    """The inverse is exact for any origin away from the poles."""
    origin = ReferenceOrigin(lat0, lon0)
    lat, lon = local_cartesian_to_gps(x, y, origin)
    x2, y2 = gps_to_local_cartesian(lat, lon, origin)
    assert math.hypot(float(x2) - x, float(y2) - y) < 1e-6


def test_seed_projection_against_wgs84_at_37_5_deg() -> None:
    """The sphere overstates northing by 0.300 % and understates easting by 0.124 %."""
    lat, lon = local_cartesian_to_gps(np.array([100.0, 0.0]), np.array([0.0, 100.0]))
    east, north, _ = geodetic_to_enu(lat, lon)
    # Easting: seed 100 m is 100 * N / a m in WGS84 (N the prime-vertical radius).
    assert_allclose(east[0] / 100.0 - 1.0, 0.00124, atol=0.00002)
    # Northing: seed 100 m is 100 * M / a m (M the meridian radius), 0.30 % less.
    assert_allclose(1.0 - north[1] / 100.0, 0.00298, atol=0.00002)
    # Worked from the WGS84 radii of curvature at 37.54 deg.
    e2 = 6.69437999014e-3
    s2 = math.sin(math.radians(DEFAULT_ORIGIN.lat_deg)) ** 2
    n_radius = R_EARTH / math.sqrt(1 - e2 * s2)
    m_radius = R_EARTH * (1 - e2) / (1 - e2 * s2) ** 1.5
    assert_allclose(east[0], 100.0 * n_radius / R_EARTH, atol=2e-4)
    assert_allclose(north[1], 100.0 * m_radius / R_EARTH, atol=2e-4)


def test_wgs84_round_trip() -> None:
    """ENU -> geodetic -> ENU is exact to 1e-6 m."""
    rng = np.random.default_rng(0)
    e, n, u = rng.uniform(-2000, 2000, (3, 50))
    lat, lon, alt = enu_to_geodetic(e, n, u)
    e2, n2, u2 = geodetic_to_enu(lat, lon, alt)
    assert_allclose(np.stack([e2, n2, u2]), np.stack([e, n, u]), atol=1e-6)


@pytest.mark.parametrize(
    ("lat", "lon", "message"),
    [
        (float("nan"), 127.0, "finite"),
        (37.0, float("inf"), "finite"),
        (91.0, 127.0, "latitude out of range"),
        (37.0, 181.0, "longitude out of range"),
    ],
)
def test_bad_lat_lon_rejected(lat: float, lon: float, message: str) -> None:
    """NaN, inf and out-of-range coordinates raise GeodesyError naming the problem."""
    with pytest.raises(GeodesyError, match=message):
        gps_to_local_cartesian(lat, lon)


def test_across_the_antimeridian_the_short_way_round() -> None:
    """An origin 11 m west of the antimeridian (at the equator, 1 deg = 111,319.49 m
    east): a fix 21 m east of it, past 180 deg, is x = 21 m, not 40,000 km west;
    the inverse wraps the longitude back into [-180, 180]."""
    metre = 360.0 / (2.0 * math.pi * R_EARTH)  # [deg] one metre east at the equator
    origin = ReferenceOrigin(0.0, 180.0 - 11.0 * metre)
    x, y = gps_to_local_cartesian(0.0, -180.0 + 10.0 * metre, origin)
    assert_allclose([float(x), float(y)], [21.0, 0.0], atol=1e-6)
    lat, lon = local_cartesian_to_gps(21.0, 0.0, origin)
    assert_allclose([float(lat), float(lon)], [0.0, -180.0 + 10.0 * metre], atol=1e-9)


def test_latitude_and_longitude_of_different_shapes_rejected() -> None:
    """(3,) latitudes with (2,) longitudes: one GeodesyError naming both shapes."""
    with pytest.raises(GeodesyError, match=r"one shape, got \(3,\) and \(2,\)"):
        gps_to_local_cartesian([37.5, 37.5, 37.5], [127.0, 127.0])
    with pytest.raises(GeodesyError, match="x and y must have one shape"):
        local_cartesian_to_gps([1.0, 2.0], [1.0])


def test_bad_origin_rejected() -> None:
    """An origin at the pole (cos(lat0) = 0) or out of range is refused."""
    with pytest.raises(GeodesyError, match="poles"):
        ReferenceOrigin(90.0, 0.0)
    with pytest.raises(GeodesyError, match="longitude"):
        ReferenceOrigin(0.0, 200.0)
