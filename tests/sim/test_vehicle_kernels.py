"""The car model's compiled kernels give the readable formulation's numbers, bit for bit."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from conesim.sim import kernel_math, tyres, vehicle_dynamics
from conesim.sim.tyres import PacejkaParams
from conesim.sim.vehicle_dynamics import BodyVelocity, packed
from conesim.sim.vehicle_params import VehicleParams
from tests.sim import vehicle_reference as ref

PARAMS = (
    VehicleParams(),
    dataclasses.replace(
        VehicleParams(),
        cg_to_front=0.6,
        cg_height=0.0,
        mu=0.7,
        drive_front_share=0.3,
        tyre_front=PacejkaParams(10.0, 1.5, 1.3, 0.2),
        lift_area=0.0,
    ),
)


def _cases(rng: np.random.Generator, n: int) -> list[tuple[float, ...]]:
    """(vx, vy, r, steer, accel, ax_prev, dt, heading_change): rest, creeping,
    the blend, racing speeds, rolling backwards, hard braking, collisions' rates."""
    vx = np.concatenate([
        np.zeros(5), rng.uniform(-0.5, 0.5, n), rng.uniform(0.5, 4.0, n), rng.uniform(4.0, 30.0, n)
    ])  # fmt: skip
    m = len(vx)
    rows = np.column_stack([
        vx,
        rng.normal(0.0, 0.5, m) * rng.choice([0.0, 1.0, 10.0], m),
        rng.normal(0.0, 1.0, m) * rng.choice([0.0, 1.0, 8.0], m),
        rng.uniform(-0.47, 0.47, m),
        rng.uniform(-10.0, 3.0, m),
        rng.uniform(-12.0, 12.0, m),
        rng.choice([0.005, 0.01], m),
        rng.normal(0.0, 0.01, m),
    ])  # fmt: skip
    return [tuple(float(v) for v in row) for row in rows]


@pytest.mark.parametrize("p", PARAMS)
def test_blended_wrench_is_the_reference(p: VehicleParams) -> None:
    """Every regime (kinematic, blended, dynamic; stick and slip; the friction
    caps): the compiled wrench and each of its parts equal the Python ones exactly."""
    rng = np.random.default_rng(11)
    regimes = set()
    for vx, vy, r, steer, accel, ax_prev, dt, turn in _cases(rng, 400):
        vel = BodyVelocity(vx, vy, r)
        got = vehicle_dynamics.blended_wrench(
            p, vel, steer, accel, ax_prev=ax_prev, dt=dt, heading_change=turn
        )
        want = ref.blended_wrench(p, vel, steer, accel, ax_prev=ax_prev, dt=dt, heading_change=turn)
        assert got == want
        assert vehicle_dynamics.wrench(packed(p), vx, vy, r, steer, accel, ax_prev, dt, turn) == (
            tuple(want)
        )
        loads = ref.axle_loads(p, vx, ax_prev)
        assert vehicle_dynamics.axle_loads(p, vx, ax_prev) == loads
        assert vehicle_dynamics.resistance_magnitude(p, vx, loads) == ref.resistance_magnitude(
            p, vx, loads
        )
        demand = ref.drive_brake_demand(p, accel, vx, loads)
        assert vehicle_dynamics.drive_brake_demand(p, accel, vx, loads) == demand
        lon = ref.longitudinal_forces(p, accel, vx, loads, dt)
        assert vehicle_dynamics.longitudinal_forces(p, accel, vx, loads, dt) == lon
        assert vehicle_dynamics.dynamic_wrench(p, vel, steer, loads, lon) == ref.dynamic_wrench(
            p, vel, steer, loads, lon
        )
        assert vehicle_dynamics.kinematic_wrench(
            p, vel, steer, loads, lon, dt=dt, heading_change=turn
        ) == ref.kinematic_wrench(p, vel, steer, loads, lon, dt=dt, heading_change=turn)
        speed = float(np.hypot(vx, vy))
        w = ref.blend_weight(p, speed)
        assert vehicle_dynamics.blend_weight(p, speed) == w
        stick = abs(lon.resistance) < ref.resistance_magnitude(p, vx, loads)
        model = "kinematic" if w <= 0.0 else "dynamic" if w >= 1.0 else "blend"
        regimes.update(
            (model, "brake" if demand[1] > 0.0 else "drive", "stick" if stick else "slip")
        )
    assert regimes == {"kinematic", "blend", "dynamic", "brake", "drive", "stick", "slip"}


def test_tyre_kernels_are_the_reference() -> None:
    """Slip angles, the magic formula and the friction ellipse, compiled, are the
    Python formulas' numbers (slow rolling, backwards, sliding sideways, no load)."""
    rng = np.random.default_rng(5)
    tyre = PacejkaParams()
    for _ in range(500):
        vx, vy, r, steer = rng.normal(0.0, 5.0), rng.normal(0.0, 1.0), rng.normal(), rng.normal()
        lf, lr = 0.765, 0.765
        assert tyres.slip_angles(vx, vy, r, steer, lf=lf, lr=lr) == ref.slip_angles(
            vx, vy, r, steer, lf=lf, lr=lr
        )
        alpha, fz = rng.normal(0.0, 0.3), rng.choice([0.0, rng.uniform(0.0, 2000.0)])
        fy0 = tyres.lateral_force(alpha, fz, tyre, 0.9)
        assert fy0 == ref.lateral_force(alpha, fz, tyre, 0.9)
        fx = rng.normal(0.0, 3000.0)
        assert tyres.friction_ellipse(fx, fy0, fz, 1.44) == ref.friction_ellipse(fx, fy0, fz, 1.44)


def test_py_min_and_max_are_pythons() -> None:
    """Ties (0.0 and -0.0) keep the first argument, as Python's ``min`` and ``max`` do."""
    for a, b in ((0.0, -0.0), (-0.0, 0.0), (1.0, 2.0), (2.0, 1.0)):
        assert str(kernel_math.py_min(a, b)) == str(min(a, b))
        assert str(kernel_math.py_max(a, b)) == str(max(a, b))


def test_packed_follows_the_layout() -> None:
    """The packed array holds each parameter at its index, derived ones as the
    properties give them (lr = L - lf = 1.53 - 0.765, mu_front = mu * D = 1.6)."""
    p = VehicleParams()
    q = packed(p)
    assert q.shape == (vehicle_dynamics.N_PARAMS,)
    assert not q.flags.writeable
    assert q[vehicle_dynamics.MASS] == 190.0
    assert q[vehicle_dynamics.LR] == p.wheelbase - p.cg_to_front
    assert q[vehicle_dynamics.MU_FRONT] == 1.6
    assert q[vehicle_dynamics.REAR_E] == -0.58
    assert packed(dataclasses.replace(p)) is q  # one array per parameter set
