"""Tests for envs.scenario: the Scenario type, its resolution and the loop it builds."""

from __future__ import annotations

import dataclasses

import pytest

from conesim.envs.scenario import Scenario
from conesim.localization.ekf import PROFILES as EKF_PROFILES
from conesim.localization.ekf import EkfConfig
from conesim.planner import AutopilotConfig
from conesim.sim.sensors import ConeFaults, Faults, GpsFaults, get_profile, override
from conesim.sim.vehicle_params import VehicleParams
from conesim.tracks import load_track


def test_the_defaults_are_conesim_runs() -> None:
    """trackdrive, one lap, seed 0, rtk, fused, 50/200 Hz, no faults, the rtk tuning."""
    s = Scenario()
    assert (s.track, s.laps, s.seed, s.localization) == ("trackdrive", 1, 0, "fused")
    assert (s.control_rate, s.physics_rate, s.time_limit) == (50.0, 200.0, None)
    assert s.sensors == get_profile("rtk") and s.faults == Faults()
    assert s.ekf_config() == EKF_PROFILES["rtk"] and s.ekf_tuning_name == "rtk"
    assert s.autopilot_config() == AutopilotConfig()
    assert s.rules.time_limit_s == 90.0


def test_resolution_follows_the_sensors_and_the_localization() -> None:
    """Left open, the tuning and the autopilot follow a replaced part: consumer
    sensors get consumer's tuning, the raw pose the cautious autopilot."""
    s = dataclasses.replace(Scenario(), sensors=get_profile("consumer"), localization="raw")
    assert s.ekf_tuning_name == "consumer" and s.ekf_config() == EKF_PROFILES["consumer"]
    assert s.autopilot_config() == AutopilotConfig.cautious()
    full = s.resolved()
    assert full.ekf == EKF_PROFILES["consumer"] and full.ekf_tuning == "consumer"
    assert full.autopilot == AutopilotConfig.cautious()
    assert full.resolved() == full


def test_named_and_custom_tunings() -> None:
    """A named tuning is the shipped one as it is; 'custom' EkfConfig's defaults; a
    given EkfConfig is used as given and reported as custom."""
    on_rtk = Scenario(ekf_tuning="consumer")
    assert on_rtk.ekf_config() == EKF_PROFILES["consumer"]  # a deliberate mismatch
    assert Scenario(ekf_tuning="custom").ekf_config() == EkfConfig()
    given = EkfConfig(gate_probability=0.99)
    assert Scenario(ekf=given).ekf_config() is given
    assert Scenario(ekf=given).ekf_tuning_name == "custom"
    assert Scenario(ekf=given, ekf_tuning="consumer").ekf_tuning_name == "consumer"


def test_the_faults_reach_the_world_but_not_the_filter() -> None:
    """A 0.7 detection probability and a GPS dropout are in the world's sensors; the
    filter is matched to the sensors before them (and rtk's is unchanged)."""
    faults = Faults(cones=ConeFaults(detection_probability=0.7),
                    gps=GpsFaults(dropouts=((10.0, 12.0),)))  # fmt: skip
    s = Scenario(track="acceleration", faults=faults)
    world = s.world_config()
    assert world.sensor_profile.cones.detection_probability_at_zero == 0.7
    assert world.sensor_profile.gps.dropouts == ((10.0, 2.0),)
    assert s.ekf_config() == EKF_PROFILES["rtk"]
    loop = s.closed_loop(load_track("acceleration"))
    loop.reset(0)
    assert loop.world.sensors.cones.config.detection_probability_at_zero == 0.7
    assert loop.ekf_config == EKF_PROFILES["rtk"]


def test_an_overridden_receiver_gets_a_filter_that_models_it() -> None:
    """rtk with a 0.5 m GPS bias: the matched filter carries the bias state; a
    fault (a drift) is not told to it."""
    biased = override(get_profile("rtk"), {"gps.bias_sigma": 0.5})
    drift = Faults(gps=GpsFaults(bias_drift=(0.1, 0.0)))
    s = Scenario(sensors=biased, faults=drift)
    assert s.ekf_config().gps_bias_sigma == 0.5 and s.ekf_config().layout.gps_bias
    assert s.ekf_config().gps_bias_tau == 60.0
    assert s.world_config().sensor_profile.gps.drift_rate == (0.1, 0.0)


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"laps": 0}, "Scenario.laps = 0 is out of range: allowed [1, 100]"),
        ({"laps": 101}, "Scenario.laps = 101 is out of range: allowed [1, 100]"),
        ({"seed": -1}, "Scenario.seed = -1 is out of range: allowed [0, 2**63)"),
        ({"seed": 2**63}, "allowed [0, 2**63)"),
        ({"control_rate": 0.0}, "Scenario.control_rate = 0.0 is out of range: allowed [1, 1000]"),
        ({"control_rate": 1e-3, "physics_rate": 1e-3}, "control_rate = 0.001 is out of range"),
        ({"physics_rate": 1e7}, "Scenario.physics_rate = 10000000.0 is out of range: allowed"),
        (
            {"faults": Faults(cones=ConeFaults(false_positives_per_scan=100.0))},
            "Scenario: the sensors with their faults: ConeDetectorConfig.false_positive_rate "
            "= 100.1 is out of range: allowed [0, 100] [1/scan]",
        ),
        ({"control_rate": 30.0}, "physics_rate (200.0 Hz) must be a whole multiple"),
        (
            {"localization": "gps"},
            "Scenario.localization = 'gps': allowed fused, raw, truth, cones",
        ),
        ({"ekf_tuning": "fast"}, "Scenario.ekf_tuning = 'fast': allowed auto, ideal, rtk,"),
        ({"time_limit": -1.0}, "EpisodeRules.time_limit must be finite and > 0 [s]"),
        ({"track": " "}, "Scenario.track = ' ': give a shipped track name or a file"),
    ],
)
def test_bad_values_are_refused_when_made(changes: dict[str, object], message: str) -> None:
    """Each out-of-range field raises ValueError naming it and the range."""
    with pytest.raises(ValueError) as info:
        Scenario(**changes)  # type: ignore[arg-type]
    assert message in str(info.value)


def test_a_part_must_be_its_config() -> None:
    """A mapping where a config belongs is a TypeError that says where mappings go."""
    with pytest.raises(TypeError, match=r"Scenario\.vehicle must be a VehicleParams, got dict"):
        Scenario(vehicle={"mass": 200.0})  # type: ignore[arg-type]
    assert Scenario(vehicle=VehicleParams(mass=200.0)).world_config().vehicle.mass == 200.0


def test_rates_and_limits_are_plain_floats() -> None:
    """An int rate or limit becomes a float: the clock's type, and so the run, stays."""
    s = Scenario(control_rate=50, physics_rate=200, time_limit=30)
    assert type(s.control_rate) is float and type(s.time_limit) is float
    assert s == Scenario(control_rate=50.0, physics_rate=200.0, time_limit=30.0)


def test_a_scenario_pickles_for_worker_processes() -> None:
    """A sweep runs scenarios in worker processes: one pickles and compares equal."""
    import pickle

    s = Scenario(sensors=get_profile("consumer"), faults=Faults(gps=GpsFaults(multipath_rate=0.1)))
    assert pickle.loads(pickle.dumps(s)) == s
    assert pickle.loads(pickle.dumps(s.resolved())) == s.resolved()
