"""Tests of the vehicle parameter validation."""

from __future__ import annotations

import dataclasses
import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from conesim.sim.vehicle_params import VehicleParams


def test_defaults_are_the_fssim_car() -> None:
    """fssim gotthard: 190 kg, 110 kg m^2, L = 1.53 m, 50/50, peak mu 1.6."""
    p = VehicleParams()
    assert (p.mass, p.yaw_inertia, p.wheelbase) == (190.0, 110.0, 1.53)
    assert p.cg_to_rear == pytest.approx(0.765)
    assert p.mu_front == p.mu_rear == pytest.approx(1.6)


@pytest.mark.parametrize(
    ("name", "value", "allowed"),
    [
        ("mass", 0.0, r"\(0, inf\) \[kg\]"),
        ("mass", -190.0, r"\(0, inf\) \[kg\]"),
        ("yaw_inertia", 0.0, r"\(0, inf\)"),
        ("wheelbase", 0.0, r"\(0, inf\) \[m\]"),
        ("cg_to_front", 1.53, r"\(0, 1.53\) \[m\]"),
        ("mu", 0.0, r"\(0, inf\) \[-\]"),
        ("steer_time_constant", -0.01, r"\[0, inf\) \[s\]"),
        ("max_steer", 2.0, r"\(0, 1.5708\) \[rad\]"),
        ("max_steer_rate", 0.0, r"\(0, inf\) \[rad/s\]"),
        ("max_decel", -10.0, r"\(0, inf\)"),
        ("drive_front_share", 1.5, r"\[0, 1\]"),
        ("blend_speed_high", 1.0, r"\(1.5, inf\)"),
        ("length", 1.0, r"\(1.515, inf\)"),
        ("mass", math.nan, r"finite"),
        ("antenna_x", math.inf, r"finite"),
    ],
)
def test_out_of_range_raises_naming_the_field(name: str, value: float, allowed: str) -> None:
    """Each bad value raises ValueError naming the field and its allowed range."""
    with pytest.raises(ValueError, match=rf"VehicleParams\.{name} must be.*{allowed}"):
        VehicleParams(**{name: value})


def test_params_are_frozen() -> None:
    """A parameter set cannot change after construction."""
    p = VehicleParams()
    with pytest.raises(dataclasses.FrozenInstanceError):
        p.mass = 200.0  # type: ignore[misc]


@given(mass=st.floats(1.0, 1e4), lf_ratio=st.floats(0.05, 0.95))
def test_any_physical_car_is_accepted(mass: float, lf_ratio: float) -> None:
    """Positive mass and a CG between the axles are always valid."""
    p = VehicleParams(mass=mass, cg_to_front=lf_ratio * 1.53)
    assert p.cg_to_front + p.cg_to_rear == pytest.approx(1.53)


def test_a_motor_that_cannot_beat_rolling_resistance_is_refused() -> None:
    """0.015 * 190 kg * 9.81 m/s^2 = 27.96 N at rest: a 27 N motor never moves the car."""
    with pytest.raises(ValueError, match=r"max_drive_force = 27\.0 N does not move.*27\.9585 N"):
        VehicleParams(max_drive_force=27.0)
    VehicleParams(max_drive_force=28.0)  # just enough
