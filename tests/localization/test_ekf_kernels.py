"""The compiled motion model against the numpy reference, bit for bit, over many intervals."""

from __future__ import annotations

import numpy as np
import pytest

from conesim.localization.ekf import model as m
from conesim.localization.ekf.model import ProcessModel, StateLayout
from tests.localization import ekf_reference as ref


def test_motion_step_matches_the_model_for_any_interval() -> None:
    """Random dt (the kernel's cube and exponentials against Python's), every layout."""
    rng = np.random.default_rng(12)
    layouts = [
        StateLayout(gps_bias=g, heading_bias=h) for g in (False, True) for h in (False, True)
    ]
    for layout in layouts:
        model = ProcessModel(layout, 0.01, 0.03, 0.002, 1e-4, 1e-4, 2.0, 60.0, 0.03, 30.0)
        step = m.MotionStep(model)
        for _ in range(500):
            x = rng.normal(size=(layout.n, 1)) * 5.0
            x.flags.writeable = bool(rng.integers(2))  # the filter hands over both kinds
            u = rng.normal(size=3) * [1.0, 5.0, 10.0]
            cov = np.diag(rng.uniform(1e-7, 1e-2, 3))
            dt = float(rng.uniform(1e-5, 0.3))
            x1, f, q = step(x, u, cov, dt)
            np.testing.assert_array_equal(x1, ref.motion_model(x, u, dt, model))
            np.testing.assert_array_equal(f, ref.jacob_f(x, u, dt, model))
            np.testing.assert_array_equal(q, ref.process_noise(x, u, cov, dt, model))
            assert x1.flags.writeable  # the filter wraps its yaw in place


def test_motion_step_rejects_a_wrongly_shaped_state_or_input() -> None:
    """The kernel does not check bounds: the wrapper raises, naming the shapes."""
    model = ProcessModel(StateLayout(), 0.01, 0.03, 0.002, 1e-4, 1e-4, 2.0, 60.0, 0.03, 30.0)
    step = m.MotionStep(model)
    cov = np.eye(3) * 1e-4
    with pytest.raises(ValueError, match=r"x \(4, 1\), u \(3,\); expected \(7, 1\)"):
        step(np.zeros((4, 1)), np.zeros(3), cov, 0.01)
    with pytest.raises(ValueError, match=r"u \(2,\)"):
        step(np.zeros((7, 1)), np.zeros(2), cov, 0.01)


def test_motion_step_input_jacobian_is_the_reference_bit_for_bit() -> None:
    """G, which MotionStep keeps for Q's G Sigma G', against the reference's jacob_u exactly."""
    rng = np.random.default_rng(13)
    for layout in ref.LAYOUTS:
        model = ProcessModel(layout, 0.01, 0.03, 0.002, 1e-4, 1e-4, 2.0, 60.0, 0.03, 30.0)
        step = m.MotionStep(model)
        for _ in range(100):
            x, u = ref.random_state(layout, rng), rng.normal(size=3) * [1.0, 5.0, 10.0]
            dt = float(rng.uniform(1e-5, 0.3))
            step(x, u, np.eye(3), dt)
            np.testing.assert_array_equal(step._g, ref.jacob_u(x, u, dt, model))
