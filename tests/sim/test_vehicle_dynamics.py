"""Unit tests of the single-track force model (no pymunk)."""

from __future__ import annotations

import dataclasses
import math

from numpy.testing import assert_allclose

from conesim.sim.vehicle_dynamics import (
    BodyVelocity,
    axle_loads,
    blend_weight,
    drive_brake_demand,
    dynamic_wrench,
    kinematic_wrench,
    longitudinal_forces,
)
from conesim.sim.vehicle_params import VehicleParams

P = VehicleParams()
DT = 1.0 / 200.0


def test_static_loads_split_by_cg_position() -> None:
    """Fz_f = m g lr / L = 190*9.81*0.765/1.53 = 931.95 N; the sum is m g."""
    p = dataclasses.replace(P, cg_to_front=0.6)
    loads = axle_loads(p, 0.0, 0.0)
    assert_allclose(loads.front, 190 * 9.81 * 0.93 / 1.53, rtol=1e-12)
    assert_allclose(loads.front + loads.rear, 190 * 9.81, rtol=1e-12)


def test_braking_moves_load_forward() -> None:
    """ax = -10: m a h / L = 190*10*0.262/1.53 = 325.36 N moves to the front."""
    static = axle_loads(P, 0.0, 0.0)
    braking = axle_loads(P, 0.0, -10.0)
    assert_allclose(braking.front - static.front, 325.359, rtol=1e-5)
    assert_allclose(braking.front + braking.rear, 190 * 9.81, rtol=1e-12)


def test_downforce_is_half_rho_cla_v_squared() -> None:
    """20 m/s: 0.5*1.225*3.107*400 = 761.2 N, split 50/50."""
    static = axle_loads(P, 0.0, 0.0)
    fast = axle_loads(P, 20.0, 0.0)
    assert_allclose(fast.front - static.front, 0.5 * 761.215, rtol=1e-5)
    assert_allclose(fast.rear - static.rear, 0.5 * 761.215, rtol=1e-5)


def test_demand_feeds_resistances_forward_and_respects_power() -> None:
    """10 m/s, a = 2: F = 380 + 70 + Crr*Fz; 25 m/s at full demand: P/v = 800 N."""
    loads = axle_loads(P, 10.0, 0.0)
    drive, brake = drive_brake_demand(P, 2.0, 10.0, loads)
    expected = 190 * 2.0 + 0.5 * 1.225 * 1.143 * 100 + 0.015 * (loads.front + loads.rear)
    assert_allclose(drive, expected, rtol=1e-12)
    assert brake == 0.0
    drive, _ = drive_brake_demand(P, 3.0, 25.0, axle_loads(P, 25.0, 0.0))
    assert_allclose(drive, 20_000.0 / 25.0, rtol=1e-12)


def test_no_drive_at_rest_without_positive_demand() -> None:
    """At rest a zero or negative demand never drives the car."""
    loads = axle_loads(P, 0.0, 0.0)
    assert drive_brake_demand(P, 0.0, 0.0, loads) == (0.0, 0.0)
    assert drive_brake_demand(P, -10.0, 0.0, loads) == (0.0, 1900.0)


def test_brakes_stop_the_car_exactly_and_never_reverse_it() -> None:
    """0.02 m/s under full braking: the forces bring vx to exactly 0 in one step."""
    loads = axle_loads(P, 0.0, 0.0)
    for vx in (0.0, 0.02, -0.02):
        lon = longitudinal_forces(P, -10.0, vx, loads, DT)
        total = lon.front + lon.rear + lon.resistance
        assert_allclose(vx + total * DT / P.mass, 0.0, atol=1e-15)


def test_brakes_slide_at_speed() -> None:
    """At 10 m/s, -10 m/s^2 total: brake + drag + rolling = m * 10 = 1900 N."""
    loads = axle_loads(P, 10.0, 0.0)
    lon = longitudinal_forces(P, -10.0, 10.0, loads, DT)
    assert_allclose(lon.front + lon.rear + lon.resistance, -1900.0, rtol=1e-12)
    assert_allclose(lon.front / (lon.front + lon.rear), 0.6, rtol=1e-12)


def test_linear_cornering_force_is_stiffness_times_slip() -> None:
    """Rear slip 1e-4 rad: Fy_r = B*C*D*Fz_r*alpha = 27.73*931.95*1e-4 = 2.584 N."""
    loads = axle_loads(P, 0.0, 0.0)  # no downforce at vx = 0 in the load call
    lon = longitudinal_forces(P, 0.0, 10.0, loads, DT)._replace(front=0.0, rear=0.0)
    w = dynamic_wrench(P, BodyVelocity(10.0, -1e-3, 0.0), 0.0, loads, lon)
    c_alpha = 12.56 * 1.38 * 1.6 * 931.95
    alpha = math.atan(1e-4)
    assert_allclose(w.fy, 2 * c_alpha * alpha, rtol=1e-5)
    assert_allclose(w.mz, 0.0, atol=1e-9)


def test_kinematic_wrench_reaches_the_kinematic_velocities() -> None:
    """One step of F/m, M/I from (1, 0, 0) lands on vy = vx lr tan(d)/L, r = vx tan(d)/L."""
    loads = axle_loads(P, 1.0, 0.0)
    lon = longitudinal_forces(P, 0.0, 1.0, loads, DT)
    w = kinematic_wrench(
        P, BodyVelocity(1.0, 0.0, 0.0), 0.05, loads, lon, dt=DT, heading_change=0.0
    )
    vx = 1.0 + w.fx * DT / P.mass
    vy = w.fy * DT / P.mass
    r = w.mz * DT / P.yaw_inertia
    assert_allclose(vy, vx * 0.765 * math.tan(0.05) / 1.53, rtol=1e-12)
    assert_allclose(r, vx * math.tan(0.05) / 1.53, rtol=1e-12)


def test_kinematic_wrench_is_capped_by_tyre_friction() -> None:
    """Sliding sideways at 1 m/s: |F| <= mu (Fz_f + Fz_r) = 1.6 * 1863.9 = 2982 N."""
    loads = axle_loads(P, 0.0, 0.0)
    lon = longitudinal_forces(P, 0.0, 0.0, loads, DT)
    w = kinematic_wrench(P, BodyVelocity(0.0, 1.0, 2.0), 0.0, loads, lon, dt=DT, heading_change=0.0)
    assert_allclose(math.hypot(w.fx, w.fy), 1.6 * 190 * 9.81, rtol=1e-12)
    assert w.fy < 0.0
    assert_allclose(w.mz, -1.6 * 190 * 9.81 * 0.765, rtol=1e-12)


def test_blend_weight_is_a_ramp_between_the_blend_speeds() -> None:
    """0 below 1.5 m/s, 0.5 at 2.5 m/s, 1 above 3.5 m/s (fssim)."""
    assert [blend_weight(P, v) for v in (0.0, 1.5, 2.5, 3.5, 10.0)] == [0.0, 0.0, 0.5, 1.0, 1.0]
