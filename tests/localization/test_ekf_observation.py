"""The EKF's observation models: worked values, Jacobians, the wrapped heading residual."""

from __future__ import annotations

import math

import numpy as np
import pytest

from conesim.localization.ekf.health import Sensor
from conesim.localization.ekf.model import StateLayout
from conesim.localization.ekf.observation import (
    OBSERVATIONS,
    Observation,
    h_heading,
    h_position,
    h_wheel_speed,
    heading_residual,
    jacob_h_position,
)
from tests.localization.ekf_reference import LAYOUTS, layout_id, numeric_jacobian, random_state

BOTH = StateLayout(gps_bias=True, heading_bias=True)


def worked_state() -> np.ndarray:
    """x 10 m, y 20 m, yaw 0.3 rad, vx 5 m/s, scale 1.02, GPS error (1, -2) m, heading 0.05 rad."""
    x = np.zeros((BOTH.n, 1))
    x[:, 0] = [10.0, 20.0, 0.3, 5.0, 0.1, 0.0, 1.02, 1.0, -2.0, 0.05]
    return x


def test_expected_measurements_add_the_modelled_sensor_errors() -> None:
    """GPS (11, 18) m, heading 0.35 rad, wheel speed 1.02 * 5 m/s; without biases, the state."""
    x = worked_state()
    np.testing.assert_array_equal(h_position(x, BOTH), [[11.0], [18.0]])
    np.testing.assert_array_equal(h_heading(x, BOTH), [[0.3 + 0.05]])
    np.testing.assert_array_equal(h_wheel_speed(x, BOTH), [[1.02 * 5.0]])
    core = StateLayout()
    np.testing.assert_array_equal(h_position(x[:7], core), [[10.0], [20.0]])
    np.testing.assert_array_equal(h_heading(x[:7], core), [[0.3]])


def test_position_jacobian_picks_the_position_and_the_receiver_error() -> None:
    """H = [I2 0 I2 0] with both biases in the state: ones at x, y, gps_bias_e, gps_bias_n."""
    h = jacob_h_position(worked_state(), BOTH)
    expected = np.zeros((2, 10))
    expected[0, 0] = expected[1, 1] = expected[0, 7] = expected[1, 8] = 1.0
    np.testing.assert_array_equal(h, expected)


@pytest.mark.parametrize("layout", LAYOUTS, ids=layout_id)
@pytest.mark.parametrize("sensor", list(OBSERVATIONS), ids=str)
def test_jacobians_match_finite_differences(layout: StateLayout, sensor: Sensor) -> None:
    """H = dh/dx against central differences; h has shape (m, 1); a constant H is constant."""
    obs: Observation = OBSERVATIONS[sensor]
    rng = np.random.default_rng(2)
    first = obs.jacobian(random_state(layout, rng), layout)
    for _ in range(5):
        x = random_state(layout, rng)
        numeric = numeric_jacobian(lambda xx: obs.h(xx, layout), x)
        assert obs.h(x, layout).shape == (numeric.shape[0], 1)
        np.testing.assert_allclose(obs.jacobian(x, layout), numeric, atol=1e-8)
        assert np.array_equal(obs.jacobian(x, layout), first) == obs.constant


def test_heading_residual_wraps_across_pi() -> None:
    """Measured just past -pi, predicted just below +pi: the residual is small and positive."""
    z, h = np.array([[-math.pi + 0.01]]), np.array([[math.pi - 0.02]])
    np.testing.assert_allclose(heading_residual(z, h), [[0.03]], atol=1e-12)
    np.testing.assert_allclose(heading_residual(h, z), [[-0.03]], atol=1e-12)


def test_every_measured_sensor_has_a_model_and_the_imu_none() -> None:
    """GPS, heading and wheel speed are observed; the IMU is the motion model's input."""
    assert set(OBSERVATIONS) == {Sensor.GPS, Sensor.HEADING, Sensor.WHEEL_SPEED}
    assert [OBSERVATIONS[s].constant for s in (Sensor.GPS, Sensor.HEADING)] == [True, True]
