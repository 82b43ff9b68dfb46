"""Tests for envs.runner.run_scenario's arguments (its runs: test_laps.py)."""

from __future__ import annotations

import time
from typing import Any

import pytest

from conesim.envs import runner
from conesim.envs.runner import TIMING_FIELDS, run_scenario


def test_env_options_may_not_repeat_run_scenario_arguments() -> None:
    """A field run_scenario sets itself, repeated in env_options, is one clear error."""
    with pytest.raises(ValueError, match=r"env_options \['laps'\] repeat .* pass laps= instead"):
        run_scenario("acceleration", env_options={"laps": 2})
    with pytest.raises(ValueError, match="pass render= instead"):
        run_scenario("acceleration", env_options={"render_mode": "human"})


def test_env_options_reach_the_env() -> None:
    """A further EnvConfig field (a 0.5 s time limit) ends the run: truncated."""
    result = run_scenario("acceleration", env_options={"time_limit": 0.5})
    assert not result.finished and result.end_reason == "time_limit"
    assert result.sim_time_s == pytest.approx(0.5)


def test_setup_is_timed_apart_from_the_loop(monkeypatch: pytest.MonkeyPatch) -> None:
    """Building the env (where the EKF's compiled kernels load) and the autopilot
    (the planner's) is setup_time_s, not part of the loop's wall time: an env
    that takes 0.3 s and an autopilot that takes 0.5 s to build add 0.8 s."""

    class SlowEnv(runner.ConeTrackEnv):
        def __init__(self, *args: Any, **kwargs: Any) -> None:
            time.sleep(0.3)
            super().__init__(*args, **kwargs)

    class SlowPolicy(runner.AutopilotPolicy):
        def __init__(self, *args: Any, **kwargs: Any) -> None:
            time.sleep(0.5)
            super().__init__(*args, **kwargs)

    monkeypatch.setattr(runner, "ConeTrackEnv", SlowEnv)
    monkeypatch.setattr(runner, "AutopilotPolicy", SlowPolicy)
    result = run_scenario("acceleration", env_options={"time_limit": 0.5})
    assert result.setup_time_s >= 0.8
    assert result.real_time_factor == pytest.approx(result.sim_time_s / result.wall_time_s)
    assert set(TIMING_FIELDS) <= set(result.to_json())
