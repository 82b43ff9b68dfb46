"""Tests for envs.runner.run_scenario's arguments (its runs: test_laps.py)."""

from __future__ import annotations

import time
from typing import Any

import pytest

from conesim.envs import runner, scenario
from conesim.envs.runner import TIMING_FIELDS, run_scenario


def test_a_time_limit_ends_the_run_truncated() -> None:
    """A 0.5 s time limit ends the run there: time_limit, not finished."""
    result = run_scenario("acceleration", time_limit=0.5)
    assert not result.finished and result.end_reason == "time_limit"
    assert result.sim_time_s == pytest.approx(0.5)


def test_bad_rates_are_refused_before_the_run() -> None:
    """A physics rate that is no multiple of the control rate is one clear error."""
    with pytest.raises(ValueError, match=r"physics_rate \(200.0 Hz\) must be a whole multiple"):
        run_scenario("acceleration", control_rate=30.0)


def test_setup_is_timed_apart_from_the_loop(monkeypatch: pytest.MonkeyPatch) -> None:
    """Building the loop (where the EKF's compiled kernels load) and the autopilot
    (the planner's) is setup_time_s, not part of the loop's wall time: a loop
    that takes 0.3 s and an autopilot that takes 0.5 s to build add 0.8 s."""

    class SlowLoop(scenario.ClosedLoop):
        def __init__(self, *args: Any, **kwargs: Any) -> None:
            time.sleep(0.3)
            super().__init__(*args, **kwargs)

    class SlowAutopilot(runner.Autopilot):
        def __init__(self, *args: Any, **kwargs: Any) -> None:
            time.sleep(0.5)
            super().__init__(*args, **kwargs)

    monkeypatch.setattr(scenario, "ClosedLoop", SlowLoop)
    monkeypatch.setattr(runner, "Autopilot", SlowAutopilot)
    result = run_scenario("acceleration", time_limit=0.5)
    assert result.setup_time_s >= 0.8
    assert result.real_time_factor == pytest.approx(result.sim_time_s / result.wall_time_s)
    assert set(TIMING_FIELDS) <= set(result.to_json())
