"""Tests for envs.ekf_tuning: the EKF tuning a sensor profile gets."""

from __future__ import annotations

import dataclasses
import math

import pytest

from conesim.envs.ekf_tuning import matched_ekf, tuning_name
from conesim.localization.ekf import PROFILES as EKF_PROFILES
from conesim.sim.sensors import PROFILES, get_profile, override


@pytest.mark.parametrize("name", list(PROFILES))
def test_a_shipped_profile_gets_its_shipped_tuning_exactly(name: str) -> None:
    """The match is the shipped tuning value for value: runs without a scenario stay."""
    assert tuning_name(PROFILES[name]) == name
    assert matched_ekf(PROFILES[name]) == EKF_PROFILES[name]


def test_a_profile_of_another_name_gets_rtk_with_its_own_receiver_model() -> None:
    """A profile built in code, named 'lidar_test', with a 1.5 m, 30 s GPS bias and a
    200 Hz IMU: rtk's tuning, told the bias and the rate (it used to get plain rtk)."""
    rtk = get_profile("rtk")
    mine = dataclasses.replace(
        override(rtk, {"gps.bias_sigma": 1.5, "gps.bias_tau": 30.0, "imu.rate": 200.0}),
        name="lidar_test",
    )
    assert tuning_name(mine) == "rtk"
    ekf = matched_ekf(mine)
    assert (ekf.gps_bias_sigma, ekf.gps_bias_tau, ekf.imu_rate) == (1.5, 30.0, 200.0)
    assert ekf.layout.gps_bias and not ekf.layout.heading_bias
    assert (
        dataclasses.replace(ekf, gps_bias_sigma=0.0, gps_bias_tau=60.0, imu_rate=100.0)
        == (EKF_PROFILES["rtk"])
    )


def test_an_explicit_tuning_keeps_the_receiver_model_of_the_sensors() -> None:
    """consumer's tuning on rtk sensors: consumer's gyro walk, no bias states (rtk has none)."""
    ekf = matched_ekf(get_profile("rtk"), "consumer")
    assert ekf.gyro_bias_walk == EKF_PROFILES["consumer"].gyro_bias_walk
    assert ekf.gps_bias_sigma == 0.0 and ekf.heading_bias_sigma == 0.0
    assert matched_ekf(get_profile("consumer")).heading_bias_sigma == math.radians(2.0)
    with pytest.raises(ValueError, match="unknown EKF profile 'gps_only'"):
        matched_ekf(get_profile("rtk"), "gps_only")
