"""The EKF's motion model (MotionStep, the compiled kernel): Jacobians, zero motion, a circle."""

from __future__ import annotations

import math
from functools import partial

import numpy as np
import pytest

from conesim.localization.ekf import model as m
from conesim.localization.ekf.model import MotionStep, ProcessModel, StateLayout
from tests.localization.ekf_reference import (
    LAYOUTS,
    FloatArray,
    layout_id,
    numeric_jacobian,
    random_state,
)

NO_INPUT_NOISE = np.zeros((3, 3))


def process_model(layout: StateLayout) -> ProcessModel:
    return ProcessModel(
        layout=layout,
        imu_period=0.01,
        accel_model_density=0.05,
        yaw_model_density=0.002,
        gyro_bias_walk=1e-4,
        wheel_scale_walk=1e-4,
        gps_bias_sigma=2.0,
        gps_bias_tau=60.0,
        heading_bias_sigma=0.03,
        heading_bias_tau=30.0,
    )


def next_state(step: MotionStep, x: FloatArray, u: FloatArray, dt: float) -> FloatArray:
    """x' alone."""
    return step(x, u, NO_INPUT_NOISE, dt)[0]


@pytest.mark.parametrize("layout", LAYOUTS, ids=layout_id)
@pytest.mark.parametrize("dt", [0.001, 0.01, 0.2])
def test_jacobians_match_finite_differences(layout: StateLayout, dt: float) -> None:
    """F = df/dx, and G = df/du (the kernel's, which MotionStep keeps for Q), against
    central differences of x'."""
    rng = np.random.default_rng(0)
    step = MotionStep(process_model(layout))
    for _ in range(5):
        x, u = random_state(layout, rng), rng.normal(size=3) * [0.8, 3.0, 8.0]
        f = step(x, u, NO_INPUT_NOISE, dt)[1].copy()  # the step overwrites F on its next call
        g = step._g.copy()
        np.testing.assert_allclose(
            f, numeric_jacobian(partial(next_state, step, u=u, dt=dt), x), atol=1e-7
        )
        np.testing.assert_allclose(
            g, numeric_jacobian(partial(next_state, step, x, dt=dt), u), atol=1e-7
        )


@pytest.mark.parametrize("layout", LAYOUTS, ids=layout_id)
def test_zero_motion_predict_leaves_the_state_unchanged(layout: StateLayout) -> None:
    """At rest, gyro reading its bias, no specific force: x' = x exactly (biases decay only)."""
    rng = np.random.default_rng(3)
    x = random_state(layout, rng)
    x[m.VX : m.VY + 1, 0] = 0.0
    if layout.gps_bias_index is not None:
        x[layout.gps_bias_index :, 0] = 0.0
    if layout.heading_bias_index is not None:
        x[layout.heading_bias_index, 0] = 0.0
    u = np.array([x[m.GYRO_BIAS, 0], 0.0, 0.0])
    step = MotionStep(process_model(layout))
    np.testing.assert_array_equal(step(x, u, NO_INPUT_NOISE, 0.5)[0], x)


def circle_error(dt: float) -> float:
    """Largest state error after 1 s on a 10 m circle at 10 m/s (a_y = v w) in steps of dt."""
    step = MotionStep(process_model(StateLayout()))
    v, w = 10.0, 1.0
    x = np.zeros((7, 1))
    x[m.VX, 0], x[m.WHEEL_SCALE, 0] = v, 1.0
    u = np.array([w, 0.0, v * w])
    for _ in range(round(1.0 / dt)):
        x = step(x, u, NO_INPUT_NOISE, dt)[0]
    expected = [v / w * math.sin(w), v / w * (1.0 - math.cos(w)), w, v, 0.0]
    return float(np.max(np.abs(x[:5, 0] - expected)))


def test_circle_matches_the_analytic_arc_to_second_order() -> None:
    """100 steps of 10 ms land within 1e-4 m of the arc; halving dt quarters the error."""
    coarse, fine = circle_error(0.01), circle_error(0.005)
    assert coarse < 1e-4
    assert coarse / fine == pytest.approx(4.0, rel=0.05)


def test_gauss_markov_states_decay_with_exp_minus_dt_over_tau() -> None:
    """Biases decay by exp(-dt/tau); their noise keeps the stationary variance."""
    layout = StateLayout(gps_bias=True, heading_bias=True)
    step = MotionStep(process_model(layout))
    x = np.zeros((layout.n, 1))
    x[m.WHEEL_SCALE, 0] = 1.0
    x[7:, 0] = [1.0, -2.0, 0.1]
    out, _, q = step(x, np.zeros(3), NO_INPUT_NOISE, 6.0)
    np.testing.assert_allclose(
        out[7:, 0], [math.exp(-0.1), -2 * math.exp(-0.1), 0.1 * math.exp(-0.2)]
    )
    assert q[7, 7] == pytest.approx(4.0 * (1.0 - math.exp(-0.2)))


def test_process_noise_is_symmetric_positive_semidefinite() -> None:
    """Q is symmetric and PSD, and splitting an IMU interval keeps the yaw variance."""
    layout = StateLayout(gps_bias=True, heading_bias=True)
    step = MotionStep(process_model(layout))
    rng = np.random.default_rng(4)
    x, u = random_state(layout, rng), np.array([0.5, 1.0, 5.0])
    cov = np.diag([1e-4, 1e-3, 1e-3])
    q = step(x, u, cov, 0.01)[2]
    np.testing.assert_allclose(q, q.T, atol=1e-18)
    assert np.min(np.linalg.eigvalsh(q)) > -1e-15
    half = step(x, u, cov, 0.005)[2]
    assert 2 * half[m.YAW, m.YAW] == pytest.approx(q[m.YAW, m.YAW])


def test_state_names_follow_the_layout() -> None:
    """Indices of the optional states match the names."""
    layout = StateLayout(gps_bias=True, heading_bias=True)
    assert layout.n == 10
    assert layout.names[layout.gps_bias_index or 0] == "gps_bias_e"
    assert layout.names[layout.heading_bias_index or 0] == "heading_bias"
    assert StateLayout(heading_bias=True).heading_bias_index == 7
