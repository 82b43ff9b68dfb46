"""Tests for gymnasium.make with a scenario or its parts (envs.config, ConeTrackEnv)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

from conesim import envs
from conesim.envs.config import EnvConfig
from conesim.envs.expert import AutopilotExpert
from conesim.envs.scenario import Scenario
from conesim.envs.scenario_file import load_scenario
from conesim.planner import AutopilotConfig
from conesim.sim.sensors import ConeFaults, Faults, get_profile, override
from conesim.sim.vehicle_params import VehicleParams


def rollout(steps: int = 60, **kwargs: Any) -> list[bytes]:
    """The observations of a fixed-action rollout from seed 3."""
    env = gym.make(envs.ENV_ID, **kwargs)
    obs, _ = env.reset(seed=3)
    out = [obs.tobytes()]
    for k in range(steps):
        action = np.array([0.2 * math.sin(k / 15), 0.6], dtype=np.float32)
        obs, *_ = env.step(action)
        out.append(obs.tobytes())
    env.close()
    return out


def test_a_scenario_and_its_parts_as_keywords_give_the_same_episodes() -> None:
    """scenario=Scenario(...) and the same settings as keywords: bit for bit."""
    faults = Faults(cones=ConeFaults(detection_probability=0.6, false_positives_per_scan=1.0))
    sensors = override(get_profile("consumer"), {"cones.max_range": 12.0})
    scenario = Scenario(track="autocross", sensors=sensors, faults=faults, time_limit=20.0)
    by_scenario = rollout(scenario=scenario)
    by_parts = rollout(track="autocross", sensors=sensors, time_limit=20.0,
                       faults={"cones": {"detection_probability": 0.6,
                                         "false_positives_per_scan": 1.0}})  # fmt: skip
    assert by_scenario == by_parts
    assert by_scenario != rollout(track="autocross", sensors="consumer", time_limit=20.0)


def test_keywords_beside_a_scenario_file_change_its_parts(tmp_path: Path) -> None:
    """A scenario file's settings, with laps and max_cones given beside it."""
    path = tmp_path / "s.yaml"
    path.write_text(
        "track: skidpad\nlaps: 2\nsensors: ideal\nvehicle: {mass: 210}\n"
        "faults:\n  cones: {detection_probability: 0.5}\n"
        "autopilot:\n  speed_profile: {v_max: 9.0}\n"
    )
    env = gym.make(envs.ENV_ID, scenario=str(path), laps=3, max_cones=8)
    config: EnvConfig = env.unwrapped.config  # type: ignore[attr-defined]
    assert (config.track, config.laps, config.max_cones) == ("skidpad", 3, 8)
    assert config.vehicle == VehicleParams(mass=210.0)
    env.reset(seed=0)
    loop = env.unwrapped.loop  # type: ignore[attr-defined]
    assert loop.world.sensors.cones.config.detection_probability_at_zero == 0.5
    assert loop.world_config.vehicle.mass == 210.0
    assert loop.ekf_config == Scenario(sensors=get_profile("ideal")).ekf_config()
    expert = AutopilotExpert(env)
    expert.reset(env.unwrapped._info({}))  # type: ignore[attr-defined]
    assert expert.autopilot is not None
    assert expert.autopilot.config.speed_profile.v_max == 9.0
    env.close()


def test_a_sensor_profile_object_and_reset_options() -> None:
    """sensors= takes a profile; reset(options={'sensors': ...}) a name or a profile."""
    mine = override(get_profile("rtk"), {"gps.rate": 5.0})
    env = gym.make(envs.ENV_ID, sensors=mine, time_limit=2.0)
    env.reset(seed=0)
    assert env.unwrapped.loop.world.sensors.gps.config.rate == 5.0  # type: ignore[attr-defined]
    env.reset(seed=0, options={"sensors": "ideal"})
    assert env.unwrapped.loop.world.sensors.gps.config.white_sigma == 0.0  # type: ignore[attr-defined]
    env.close()


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"scenaro": "x.yaml"}, "unknown keys ['scenaro']; allowed keys: ['track',"),
        ({"faults": {"cones": {"misses": 0.1}}}, "faults.cones.misses: unknown key 'misses'"),
        ({"vehicle": {"mass": -1.0}}, "vehicle.mass: VehicleParams.mass must be in (0, inf)"),
        ({"sensors": "gnss"}, "EnvConfig.sensors: unknown value 'gnss'"),
        ({"scenario": "missing.yaml"}, "missing.yaml: no such file"),
    ],
)
def test_bad_parts_are_refused_naming_them(kwargs: dict[str, Any], message: str) -> None:
    """Unknown keys list the allowed ones (scenario among them); a bad part names its path."""
    with pytest.raises(ValueError) as info:
        gym.make(envs.ENV_ID, **kwargs)
    assert message in str(info.value)
    assert "scenario" in str(info.value) or "scenaro" not in kwargs


def test_the_env_default_autopilot_stays_the_localizations() -> None:
    """Without a scenario's autopilot the expert drives the runner's default."""
    env = gym.make(envs.ENV_ID, localization="raw", time_limit=1.0, action="physical")
    _, info = env.reset(seed=0)
    expert = AutopilotExpert(env)
    expert.reset(info)
    assert expert.autopilot is not None
    assert expert.autopilot.config == AutopilotConfig.cautious()
    env.close()


def test_ekf_takes_a_scenario_files_forms(tmp_path: Path) -> None:
    """``ekf="consumer"`` and ``ekf={"tuning": "consumer", "gate_probability": 0.99}``
    are what the same ``ekf:`` in a scenario file gives; with ``ekf_tuning`` too, an error."""
    for value, text in (
        ("consumer", "ekf: consumer\n"),
        ({"tuning": "consumer", "gate_probability": 0.99}, "ekf: {tuning: consumer, "
         "gate_probability: 0.99}\n"),
    ):  # fmt: skip
        (tmp_path / "s.yaml").write_text(text)
        scenario = load_scenario(tmp_path / "s.yaml")
        config = EnvConfig(ekf=value)
        assert (config.ekf, config.ekf_tuning) == (scenario.ekf, scenario.ekf_tuning)
    assert config.ekf is not None and config.ekf.gate_probability == 0.99
    with pytest.raises(ValueError, match="the tuning given twice"):
        EnvConfig(ekf="consumer", ekf_tuning="rtk")
