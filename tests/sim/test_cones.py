"""Tests for sim.cones: cone bodies, ground friction, sleeping, hits and DOO."""

from __future__ import annotations

import numpy as np
import pymunk
import pytest
from numpy.testing import assert_allclose

from conesim.sim.cones import COLLISION_CAR, ConeField, ConeParams, G

DT = 1.0 / 200.0


def make_space() -> pymunk.Space:
    """A top-down space with sleeping enabled, as World sets it up."""
    space = pymunk.Space()
    space.sleep_time_threshold = 0.3
    space.idle_speed_threshold = 0.01
    return space


def ram(space: pymunk.Space, start: tuple[float, float], speed: float) -> pymunk.Body:
    """A kinematic 1.5 x 1.2 m box moving along +x at ``speed`` [m/s]."""
    body = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
    body.position = start
    body.velocity = (speed, 0.0)
    shape = pymunk.Poly.create_box(body, (1.5, 1.2))
    shape.collision_type = COLLISION_CAR
    space.add(body, shape)
    return body


def test_sliding_cone_stops_after_v2_over_2_mu_g() -> None:
    """A cone launched at 2 m/s slides v^2 / (2 mu g) = 0.340 m before stopping."""
    space = make_space()
    field = ConeField(space, np.array([[0.0, 0.0]]), ("blue",))
    field.bodies[0].velocity = (2.0, 0.0)
    t = 0.0
    for _ in range(400):
        space.step(DT)
        t += DT
    expected = 2.0**2 / (2 * 0.6 * G)
    assert_allclose(field.bodies[0].position.x, expected, rtol=0.02)
    assert field.bodies[0].velocity.length == 0.0


def test_idle_cones_sleep_and_cost_nothing() -> None:
    """After sleep_all no cone is awake; stepping keeps them asleep."""
    space = make_space()
    xy = np.column_stack([np.arange(500.0), np.zeros(500)])
    field = ConeField(space, xy, ("yellow",) * 500)
    space.step(DT)
    field.sleep_all()
    for _ in range(10):
        space.step(DT)
    assert field.awake_count == 0


def test_hit_counts_once_and_slow_push_is_not_doo() -> None:
    """A slow brush is a hit (once) but the cone stays in its box: no DOO."""
    space = make_space()
    field = ConeField(space, np.array([[0.0, 0.0], [10.0, 0.0]]), ("blue", "blue"))
    field.sleep_all()
    car = ram(space, (-0.9, 0.0), 0.3)
    t = 0.0
    for _ in range(40):  # 0.2 s at 0.3 m/s: the box pushes the cone ~3 cm
        space.step(DT)
        t += DT
        field.update(t)
    car.velocity = (0.0, 0.0)
    car.position = (-5.0, 0.0)
    for _ in range(100):
        space.step(DT)
        t += DT
        field.update(t)
    assert field.hit_ids == {0}
    assert len(field.hit_events) == 1
    assert field.doo_ids == set()


def test_fast_hit_is_down_or_out_once() -> None:
    """A 5 m/s impact knocks the cone down or out, counted once."""
    space = make_space()
    field = ConeField(space, np.array([[0.0, 0.0], [0.0, 3.0]]), ("yellow", "yellow"))
    field.sleep_all()
    ram(space, (-1.0, 0.0), 5.0)
    t = 0.0
    for _ in range(200):
        space.step(DT)
        t += DT
        field.update(t)
    assert field.doo_ids == {0}
    assert [cone for _, cone in field.doo_events] == [0]
    assert field.positions[0, 0] > 0.228  # pushed out of its box
    assert_allclose(field.positions[1], [0.0, 3.0])  # the other cone untouched


def test_big_cone_heavier_and_wider() -> None:
    """Big orange cones get the big base and mass."""
    space = make_space()
    field = ConeField(space, np.array([[0.0, 0.0], [5.0, 0.0]]), ("big_orange", "orange"))
    assert field.bodies[0].mass == ConeParams().big_mass
    assert_allclose(field.base_widths, [0.285, 0.228])


@pytest.mark.parametrize("name", ["small_mass", "mu_ground", "big_base", "tip_speed"])
def test_bad_params_name_the_field(name: str) -> None:
    """Non-positive parameters are refused with the field named."""
    with pytest.raises(ValueError, match=f"ConeParams.{name}"):
        ConeParams(**{name: 0.0})


def test_pushed_cone_falls_asleep_again() -> None:
    """After sliding to rest a knocked cone sleeps again (ground friction must not wake it)."""
    space = make_space()
    field = ConeField(space, np.array([[0.0, 0.0]]), ("blue",))
    field.bodies[0].velocity = (1.0, 0.0)
    for _ in range(200):  # 0.17 s of sliding, then the 0.3 s sleep threshold
        space.step(DT)
    assert field.bodies[0].is_sleeping
    assert field.awake_count == 0


def test_out_means_the_whole_base_left_its_square() -> None:
    """Moved 0.2 m diagonally (0.28 m away, still overlapping its 0.228 m square): not out."""
    space = make_space()
    field = ConeField(space, np.array([[0.0, 0.0], [5.0, 0.0]]), ("blue", "blue"))
    field.bodies[0].position = (0.2, 0.2)
    field.bodies[1].position = (5.0 + 0.25, 0.0)  # a full base width along x: out
    field._watch.update({0, 1})
    field.update(0.0)
    assert field.doo_ids == {1}


def test_touching_cones_are_grouped_and_the_car_is_named() -> None:
    """Cones whose bases overlap chain into one group; a group under the car says so."""
    space = make_space()
    xy = np.array([[0.0, 0.0], [0.2, 0.1], [0.4, 0.0], [5.0, 0.0], [10.0, 0.0]])
    field = ConeField(space, xy, ("blue",) * 5)
    ram(space, (10.5, 0.0), 0.0)  # its 1.5 m box covers cone 4
    groups = sorted(field.touching_groups())
    assert groups == [([0, 1, 2], False), ([3], False), ([4], True)]


def test_a_start_on_a_cone_steps_without_corrupting_pymunk() -> None:
    """A car that starts over a cone (a start pose on the lane's edge) pushes it away.

    A cone slept on its own while it touched the car crashed inside
    ``Space.step`` ("free(): invalid pointer") on the first contact: it
    stays awake now, and touching cones sleep as a group.
    """
    space = make_space()
    xy = np.array([[0.0, 0.6], [0.15, 0.75], [4.0, 0.0]])
    field = ConeField(space, xy, ("blue", "blue", "yellow"))
    car = pymunk.Body(200.0, pymunk.moment_for_box(200.0, (1.5, 1.2)))
    shape = pymunk.Poly.create_box(car, (1.5, 1.2))
    shape.collision_type = COLLISION_CAR
    space.add(car, shape)
    field.sleep_all()
    assert [b.is_sleeping for b in field.bodies] == [False, False, True]
    t = 0.0
    for _ in range(400):
        space.step(DT)
        t += DT
        field.update(t)
    assert field.hit_ids == {0}  # cone 1 touched cone 0 only
    assert field.awake_count == 0  # all idle again, asleep as Chipmunk grouped them


def test_renew_runs_as_a_new_field_after_an_overlap_was_pushed_apart() -> None:
    """Two overlapping cones (the solver pushes them apart with bias
    velocities pymunk cannot reset), renewed into a new space after a few
    steps: the same run as a new field's, bit for bit, bookkeeping cleared."""
    xy = np.array([[0.0, 0.0], [0.05, 0.01], [3.0, 0.0]])
    kinds = ("blue", "blue", "yellow")

    def run(field: ConeField, space: pymunk.Space, steps: int) -> list[tuple[float, ...]]:
        out = []
        for k in range(steps):
            space.step(DT)
            field.update((k + 1) * DT)
            out += [(*b.position, b.angle, *b.velocity, b.angular_velocity) for b in field.bodies]
        return out

    space = make_space()
    want = run(ConeField(space, xy, kinds), space, 40)
    space = make_space()
    field = ConeField(space, xy, kinds)
    run(field, space, 7)
    assert field.version > 0
    bodies = list(field.bodies)
    new = make_space()
    field.renew(new)
    assert field.bodies == bodies and not space.bodies
    assert field.version == 0 and not field.hit_ids and not field.doo_events
    assert field.positions.tobytes() == xy.tobytes()
    assert run(field, new, 40) == want
