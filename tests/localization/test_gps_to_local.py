"""The ROS pipeline's gps_to_local_cartesian node: NavSatFix -> /local_xy in reference."""

from __future__ import annotations

import logging
import math

import numpy as np
import pytest

from conesim.core.geodesy import DEFAULT_ORIGIN, ReferenceOrigin, local_cartesian_to_gps
from conesim.core.messages import (
    FRAME_GPS_ANTENNA,
    FRAME_REFERENCE,
    Header,
    NavSatFix,
    NavSatStatus,
)
from conesim.localization.gps_to_local import GpsToLocalCartesian, gps_to_local_cartesian

R_EARTH = 6378137.0  # [m] the ROS pipeline's constant


def fix(
    lat: float, lon: float, stamp: float = 12.5, status: NavSatStatus = NavSatStatus.FIX
) -> NavSatFix:
    return NavSatFix(Header(stamp, FRAME_GPS_ANTENNA), lat, lon, 31.0, np.eye(3), status)


def seed_formula(lat: float, lon: float, origin: ReferenceOrigin) -> tuple[float, float]:
    """The ROS pipeline's C++ lines, transcribed."""
    lat_r, lon_r = math.radians(lat), math.radians(lon)
    ref_lat_r, ref_lon_r = math.radians(origin.lat_deg), math.radians(origin.lon_deg)
    x = (lon_r - ref_lon_r) * math.cos(ref_lat_r) * R_EARTH
    y = (lat_r - ref_lat_r) * R_EARTH
    return x, y


@pytest.mark.parametrize(
    ("lat", "lon"), [(37.540190, 127.076488), (37.541, 127.0751), (37.5392, 127.0779)]
)
def test_matches_the_seed_formula(lat: float, lon: float) -> None:
    """x, y equal the ROS pipeline's projection to 1e-9 m; z = 0; stamp kept; frame reference."""
    point = gps_to_local_cartesian(fix(lat, lon))
    x, y = seed_formula(lat, lon, DEFAULT_ORIGIN)
    assert point.x == pytest.approx(x, abs=1e-9)
    assert point.y == pytest.approx(y, abs=1e-9)
    assert point.z == 0.0
    assert point.header.stamp == 12.5
    assert point.header.frame_id == FRAME_REFERENCE


def test_round_trips_with_the_simulators_inverse() -> None:
    """local_cartesian_to_gps then the node returns the point to 1e-9 m."""
    origin = ReferenceOrigin(47.0, 8.0)
    lat, lon = local_cartesian_to_gps(123.4, -56.7, origin)
    point = gps_to_local_cartesian(fix(float(lat), float(lon)), origin)
    np.testing.assert_allclose([point.x, point.y], [123.4, -56.7], atol=1e-9)


@pytest.mark.parametrize(
    ("msg", "reason"),
    [
        (fix(37.54, 127.07, status=NavSatStatus.NO_FIX), "no_fix"),
        (fix(math.nan, 127.07), "invalid"),
        (fix(37.54, math.inf), "invalid"),
        (fix(95.0, 127.07), "invalid"),
        (fix(37.54, 127.07, stamp=math.nan), "invalid"),
    ],
    ids=["no_fix", "nan_lat", "inf_lon", "lat_out_of_range", "nan_stamp"],
)
def test_node_drops_fixes_without_a_position(
    msg: NavSatFix, reason: str, caplog: pytest.LogCaptureFixture
) -> None:
    """NO_FIX or an unusable position: None, counted and logged."""
    node = GpsToLocalCartesian()
    with caplog.at_level(logging.WARNING):
        assert node(msg) is None
    assert node.dropped == {reason: 1}
    assert reason in caplog.text


def test_node_converts_good_fixes() -> None:
    """A good fix goes through the node unchanged from the function."""
    node = GpsToLocalCartesian()
    point = node(fix(37.541, 127.0751))
    assert point == gps_to_local_cartesian(fix(37.541, 127.0751))
    assert not node.dropped


def test_one_fix_is_the_array_projection_bit_for_bit() -> None:
    """The node's float path for one fix gives geodesy's (numpy) projection exactly,
    near and far from several origins, at the range limits, with the sign of zero."""
    from conesim.core.geodesy import gps_to_local_cartesian as project

    rng = np.random.default_rng(3)
    origins = [DEFAULT_ORIGIN, ReferenceOrigin(-33.9, 151.2), ReferenceOrigin(0.0, 0.0)]
    for k in range(30_000):
        origin = origins[k % 3]
        if k % 3 == 0:
            lat, lon = rng.uniform(-90.0, 90.0), rng.uniform(-180.0, 180.0)
        else:
            spread = 10.0 ** rng.integers(-5, 0)
            lat = min(90.0, max(-90.0, origin.lat_deg + rng.normal() * spread))
            lon = min(180.0, max(-180.0, origin.lon_deg + rng.normal() * spread))
        cases = [(float(lat), float(lon))]
        if k == 0:
            cases += [(90.0, 180.0), (-90.0, -180.0), (0.0, -0.0), (-0.0, 0.0)]
        for la, lo in cases:
            point = gps_to_local_cartesian(fix(la, lo), origin)
            x, y = (float(v) for v in project(la, lo, origin))
            for got, want in ((point.x, x), (point.y, y)):
                assert got == want and math.copysign(1.0, got) == math.copysign(1.0, want)
