"""The EKF's motion and observation models: Jacobians, zero motion, a circle, wrapping."""

from __future__ import annotations

import math
from collections.abc import Callable
from functools import partial

import numpy as np
import pytest
from numpy.typing import NDArray

from conesim.localization.ekf import model as m
from conesim.localization.ekf.filter import heading_residual
from conesim.localization.ekf.model import ProcessModel, StateLayout

FloatArray = NDArray[np.float64]
LAYOUTS = [
    StateLayout(),
    StateLayout(gps_bias=True),
    StateLayout(heading_bias=True),
    StateLayout(gps_bias=True, heading_bias=True),
]


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


def random_state(layout: StateLayout, rng: np.random.Generator) -> FloatArray:
    x = rng.normal(size=(layout.n, 1))
    x[m.YAW, 0] = rng.uniform(-3.0, 3.0)
    x[m.VX, 0] = rng.uniform(2.0, 15.0)
    x[m.GYRO_BIAS, 0] *= 0.01
    x[m.WHEEL_SCALE, 0] = 1.0 + 0.01 * rng.normal()
    return x


def numeric_jacobian(f: Callable[[FloatArray], FloatArray], x: FloatArray) -> FloatArray:
    """Central differences, column by column."""
    x = np.asarray(x, dtype=float)
    flat = x.reshape(-1)
    cols = []
    for i in range(flat.size):
        h = 1e-6 * max(1.0, abs(flat[i]))
        up, down = flat.copy(), flat.copy()
        up[i] += h
        down[i] -= h
        cols.append((f(up.reshape(x.shape)) - f(down.reshape(x.shape))).reshape(-1) / (2.0 * h))
    return np.array(cols).T


@pytest.mark.parametrize("layout", LAYOUTS, ids=lambda lay: "-".join(lay.names[7:]) or "core")
@pytest.mark.parametrize("dt", [0.001, 0.01, 0.2])
def test_jacob_f_matches_finite_differences(layout: StateLayout, dt: float) -> None:
    """F = df/dx against central differences."""
    rng = np.random.default_rng(0)
    model = process_model(layout)
    for _ in range(5):
        x, u = random_state(layout, rng), rng.normal(size=3) * [0.8, 3.0, 8.0]
        numeric = numeric_jacobian(partial(m.motion_model, u=u, dt=dt, model=model), x)
        np.testing.assert_allclose(m.jacob_f(x, u, dt, model), numeric, atol=1e-7)


@pytest.mark.parametrize("layout", LAYOUTS, ids=lambda lay: "-".join(lay.names[7:]) or "core")
@pytest.mark.parametrize("dt", [0.001, 0.01, 0.2])
def test_jacob_u_matches_finite_differences(layout: StateLayout, dt: float) -> None:
    """G = df/du against central differences."""
    rng = np.random.default_rng(1)
    model = process_model(layout)
    for _ in range(5):
        x, u = random_state(layout, rng), rng.normal(size=3) * [0.8, 3.0, 8.0]
        numeric = numeric_jacobian(partial(m.motion_model, x, dt=dt, model=model), u)
        np.testing.assert_allclose(m.jacob_u(x, u, dt, model), numeric, atol=1e-7)


@pytest.mark.parametrize("layout", LAYOUTS, ids=lambda lay: "-".join(lay.names[7:]) or "core")
@pytest.mark.parametrize(
    ("h", "jac"),
    [
        (m.h_position, m.jacob_h_position),
        (m.h_heading, m.jacob_h_heading),
        (m.h_wheel_speed, m.jacob_h_wheel_speed),
    ],
    ids=["position", "heading", "wheel_speed"],
)
def test_observation_jacobians_match_finite_differences(
    layout: StateLayout,
    h: Callable[[FloatArray, StateLayout], FloatArray],
    jac: Callable[[FloatArray, StateLayout], FloatArray],
) -> None:
    """H = dh/dx against central differences, and h has shape (m, 1)."""
    rng = np.random.default_rng(2)
    for _ in range(5):
        x = random_state(layout, rng)
        numeric = numeric_jacobian(lambda xx: h(xx, layout), x)
        assert h(x, layout).shape == (numeric.shape[0], 1)
        np.testing.assert_allclose(jac(x, layout), numeric, atol=1e-8)


@pytest.mark.parametrize("layout", LAYOUTS, ids=lambda lay: "-".join(lay.names[7:]) or "core")
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
    np.testing.assert_array_equal(m.motion_model(x, u, 0.5, process_model(layout)), x)


def circle_error(dt: float) -> float:
    """Largest state error after 1 s on a 10 m circle at 10 m/s (a_y = v w) in steps of dt."""
    model = process_model(StateLayout())
    v, w = 10.0, 1.0
    x = np.zeros((7, 1))
    x[m.VX, 0], x[m.WHEEL_SCALE, 0] = v, 1.0
    u = np.array([w, 0.0, v * w])
    for _ in range(round(1.0 / dt)):
        x = m.motion_model(x, u, dt, model)
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
    model = process_model(layout)
    x = np.zeros((layout.n, 1))
    x[m.WHEEL_SCALE, 0] = 1.0
    x[7:, 0] = [1.0, -2.0, 0.1]
    out = m.motion_model(x, np.zeros(3), 6.0, model)
    np.testing.assert_allclose(
        out[7:, 0], [math.exp(-0.1), -2 * math.exp(-0.1), 0.1 * math.exp(-0.2)]
    )
    q = m.process_noise(x, np.zeros(3), np.zeros((3, 3)), 6.0, model)
    assert q[7, 7] == pytest.approx(4.0 * (1.0 - math.exp(-0.2)))


def test_process_noise_is_symmetric_positive_semidefinite() -> None:
    """Q is symmetric and PSD, and splitting an IMU interval keeps the yaw variance."""
    layout = StateLayout(gps_bias=True, heading_bias=True)
    model = process_model(layout)
    rng = np.random.default_rng(4)
    x, u = random_state(layout, rng), np.array([0.5, 1.0, 5.0])
    cov = np.diag([1e-4, 1e-3, 1e-3])
    q = m.process_noise(x, u, cov, 0.01, model)
    np.testing.assert_allclose(q, q.T, atol=1e-18)
    assert np.min(np.linalg.eigvalsh(q)) > -1e-15
    half = m.process_noise(x, u, cov, 0.005, model)
    assert 2 * half[m.YAW, m.YAW] == pytest.approx(q[m.YAW, m.YAW])


def test_heading_residual_wraps_across_pi() -> None:
    """Measured just past -pi, predicted just below +pi: the residual is small and positive."""
    z, h = np.array([[-math.pi + 0.01]]), np.array([[math.pi - 0.02]])
    np.testing.assert_allclose(heading_residual(z, h), [[0.03]], atol=1e-12)
    np.testing.assert_allclose(heading_residual(h, z), [[-0.03]], atol=1e-12)


def test_state_names_follow_the_layout() -> None:
    """Indices of the optional states match the names."""
    layout = StateLayout(gps_bias=True, heading_bias=True)
    assert layout.n == 10
    assert layout.names[layout.gps_bias_index or 0] == "gps_bias_e"
    assert layout.names[layout.heading_bias_index or 0] == "heading_bias"
    assert StateLayout(heading_bias=True).heading_bias_index == 7
