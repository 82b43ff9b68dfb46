"""Tests for sim.sensors.profiles and the configs' range checks."""

from __future__ import annotations

import math
from dataclasses import FrozenInstanceError
from typing import Any

import pytest
from numpy.testing import assert_allclose

from conesim.sim.sensors.cone_detector import ConeDetectorConfig
from conesim.sim.sensors.gps import GpsConfig
from conesim.sim.sensors.heading import HeadingConfig
from conesim.sim.sensors.imu import ImuConfig
from conesim.sim.sensors.profiles import PROFILES, get_profile, override
from conesim.sim.sensors.wheel_speed import WheelSpeedConfig

BAD_CONFIGS: list[tuple[type, dict[str, Any], str, str]] = [
    (GpsConfig, {"rate": 0.0}, "GpsConfig.rate", "(0, inf) [Hz]"),
    (GpsConfig, {"rate": math.nan}, "GpsConfig.rate", "(0, inf) [Hz]"),
    (GpsConfig, {"latency": -0.1}, "GpsConfig.latency", "[0, inf) [s]"),
    (GpsConfig, {"white_sigma": -1.0}, "GpsConfig.white_sigma", "[0, inf) [m]"),
    (GpsConfig, {"bias_tau": 0.0}, "GpsConfig.bias_tau", "(0, inf) [s]"),
    (GpsConfig, {"multipath_probability": 1.5}, "GpsConfig.multipath_probability", "[0, 1]"),
    (GpsConfig, {"dropouts": ((1.0, 0.0),)}, "GpsConfig.dropouts[0].duration", "(0, inf)"),
    (GpsConfig, {"dropout_mode": "off"}, "GpsConfig.dropout_mode", "'no_fix', 'silent'"),
    (
        GpsConfig,
        {"drift_rate": (math.nan, 0.0)},
        "GpsConfig.drift_rate[0]",
        "(-inf, inf) (east, north) [m/s]",
    ),
    (GpsConfig, {"drift_rate": (1.0,)}, "GpsConfig.drift_rate", "a pair of finite numbers"),
    (GpsConfig, {"drift_start": -1.0}, "GpsConfig.drift_start", "[0, inf) [s]"),
    (HeadingConfig, {"white_sigma": -0.01}, "HeadingConfig.white_sigma", "[0, inf) [rad]"),
    (HeadingConfig, {"dropouts": ((1.0, -1.0),)}, "HeadingConfig.dropouts[0].duration", "(0, inf)"),
    (HeadingConfig, {"phase": -1.0}, "HeadingConfig.phase", "[0, inf) [s]"),
    (ImuConfig, {"rate": -100.0}, "ImuConfig.rate", "(0, inf) [Hz]"),
    (ImuConfig, {"gyro_noise_density": -1.0}, "ImuConfig.gyro_noise_density", "[0, inf)"),
    (ImuConfig, {"gyro_bias": math.inf}, "ImuConfig.gyro_bias", "(-inf, inf) [rad/s]"),
    (
        ImuConfig,
        {"accel_bias": (0.1, 0.2, 0.3)},
        "ImuConfig.accel_bias",
        "a pair of finite numbers",
    ),
    (ImuConfig, {"noise_scale": -2.0}, "ImuConfig.noise_scale", "[0, inf) [-]"),
    (WheelSpeedConfig, {"scale_sigma": -0.1}, "WheelSpeedConfig.scale_sigma", "[0, inf)"),
    (WheelSpeedConfig, {"slip_sigma": -0.1}, "WheelSpeedConfig.slip_sigma", "[0, inf)"),
    (ConeDetectorConfig, {"min_range": 20.0}, "ConeDetectorConfig.min_range", "[0, max_range"),
    (ConeDetectorConfig, {"fov": 0.0}, "ConeDetectorConfig.fov", "(0, 6.28319] [rad]"),
    (ConeDetectorConfig, {"fov": 7.0}, "ConeDetectorConfig.fov", "(0, 6.28319] [rad]"),
    (ConeDetectorConfig, {"range_sigma": -0.05}, "ConeDetectorConfig.range_sigma", "[0, inf)"),
    (
        ConeDetectorConfig,
        {"detection_probability_at_zero": 1.2},
        "ConeDetectorConfig.detection_probability_at_zero",
        "[0, 1]",
    ),
    (ConeDetectorConfig, {"colour_probability": -0.1}, "colour_probability", "[0, 1]"),
    (ConeDetectorConfig, {"false_positive_rate": -1.0}, "false_positive_rate", "[0, 100]"),
    (ConeDetectorConfig, {"false_positive_rate": 101.0}, "false_positive_rate", "[0, 100]"),
    (
        ConeDetectorConfig,
        {"confusion": ((0.9, 0.0, 0.0, 0.0),) + ((1.0, 0.0, 0.0, 0.0),) * 3},
        "ConeDetectorConfig.confusion row 0 (true blue) sums to 0.9",
        "row-stochastic",
    ),
    (ConeDetectorConfig, {"confusion": ((1.0,),)}, "ConeDetectorConfig.confusion", "4x4"),
]


@pytest.mark.parametrize(("cls", "kwargs", "field", "allowed"), BAD_CONFIGS)
def test_bad_config_raises_naming_field_and_range(
    cls: type, kwargs: dict[str, Any], field: str, allowed: str
) -> None:
    """Out-of-range values are rejected at construction, naming the field and its range."""
    with pytest.raises(ValueError) as info:
        cls(**kwargs)
    assert field in str(info.value)
    assert allowed in str(info.value)


def test_min_range_equal_to_max_range_is_allowed() -> None:
    """min_range <= max_range (a single range ring) is a valid, if odd, detector."""
    assert ConeDetectorConfig(min_range=15.0, max_range=15.0).min_range == 15.0


def test_profiles_are_frozen_and_named() -> None:
    """The four profiles exist under their names and cannot be mutated."""
    assert set(PROFILES) == {"ideal", "rtk", "consumer", "consumer_white"}
    for name, profile in PROFILES.items():
        assert profile.name == name
    with pytest.raises(FrozenInstanceError):
        get_profile("rtk").gps.rate = 5.0  # type: ignore[misc]


def test_unknown_profile_lists_the_names() -> None:
    """get_profile('rtx') names every profile."""
    with pytest.raises(ValueError, match="ideal, rtk, consumer, consumer_white"):
        get_profile("rtx")


def test_profile_figures() -> None:
    """rtk: 2.5 cm white GPS per axis at 10 Hz;
    M8: CEP 2.5 m -> 2.1233 m per axis in both consumer variants; heading 1 + 2 deg
    -> hypot = 2.236 deg white in consumer_white."""
    rtk = get_profile("rtk")
    assert rtk.gps.bias_sigma == 0.0
    assert_allclose(rtk.gps.total_sigma, 0.025)
    assert (rtk.gps.rate, rtk.heading.rate, rtk.imu.rate) == (10.0, 20.0, 100.0)
    assert (rtk.wheel_speed.rate, rtk.cones.rate) == (50.0, 10.0)
    assert_allclose(rtk.heading.white_sigma, math.radians(0.25))
    consumer, white = get_profile("consumer").gps, get_profile("consumer_white").gps
    assert_allclose([consumer.total_sigma, white.total_sigma], 2.5 / 1.1774, rtol=1e-12)
    assert white.bias_sigma == 0.0 and consumer.bias_sigma > 0.9 * consumer.white_sigma
    heading, white_heading = get_profile("consumer").heading, get_profile("consumer_white").heading
    assert white_heading.bias_sigma == 0.0
    assert_allclose(white_heading.white_sigma, math.radians(2.2360680), rtol=1e-7)
    assert_allclose(math.hypot(heading.white_sigma, heading.bias_sigma), white_heading.white_sigma)
    assert (consumer.rate, consumer.latency) == (5.0, 0.12)
    ideal = get_profile("ideal")
    assert ideal.cones.false_positive_rate == 0.0 and not ideal.cones.occlusion
    assert ideal.gps.latency == ideal.cones.latency == 0.0


def test_override_replaces_fields_and_validates() -> None:
    """override(profile, {'gps.rate': 5.0, 'cones.occlusion': False}) changes only those."""
    rtk = get_profile("rtk")
    new = override(rtk, {"gps.rate": 5.0, "cones.occlusion": False})
    assert new.gps.rate == 5.0 and not new.cones.occlusion
    assert new.imu == rtk.imu and new.gps.white_sigma == rtk.gps.white_sigma
    assert rtk.gps.rate == 10.0
    with pytest.raises(ValueError, match=r"GpsConfig\.rate"):
        override(rtk, {"gps.rate": -5.0})


@pytest.mark.parametrize(
    ("key", "listed"),
    [
        ("lidar.rate", "gps.<field>, heading.<field>"),
        ("gps", "cones.<field>"),
        ("gps.sigma", "white_sigma, bias_sigma"),
    ],
)
def test_override_unknown_key_lists_allowed(key: str, listed: str) -> None:
    """Unknown sections or fields name the allowed ones."""
    with pytest.raises(ValueError, match="unknown override key") as info:
        override(get_profile("rtk"), {key: 1.0})
    assert listed in str(info.value)
