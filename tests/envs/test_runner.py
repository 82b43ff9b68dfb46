"""Tests for envs.runner.run_scenario's arguments (its runs: test_laps.py)."""

from __future__ import annotations

import pytest

from envs.runner import run_scenario


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
