"""Cones as small dynamic pymunk bodies that the car can hit, push and knock out.

Each cone is a pymunk body with a square footprint of its real base and its
mass. The simulation is top-down, so pymunk has no ground: ground friction is
applied by each cone's ``velocity_func`` as Coulomb friction (deceleration
``mu_ground * g`` opposing the sliding velocity, and the same on spin), which
brings a pushed cone to rest. Idle cones are put to sleep, so pymunk neither
integrates them nor calls their velocity function: a track of 500 cones costs
about what an empty one does (REFERENCES.md: 195k steps/s with idle cones
asleep against 47.6k awake, pymunk 7.3, 300 cones).

Scoring as the Formula Student rules do (2 s per cone down or out, DOO):

* a *hit* is a contact between the car and a cone (counted once per cone);
* a cone is *down or out* once, when its whole base has left its marked
  square (moved a full base width along x or y) or it was struck hard
  enough to tip over (its speed after the contact above ``tip_speed``). A 2D
  simulation cannot tip a cone, so the tip-over speed is the model of "down":
  an assumption, documented here and in ``ConeParams``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any

import numpy as np
import pymunk
from numpy.typing import NDArray
from scipy.sparse import coo_array
from scipy.sparse.csgraph import connected_components

from conesim.sim.bodies import remove_from_space, spend_bias
from conesim.sim.vehicle import VEHICLE_COLLISION_TYPE

COLLISION_CAR = VEHICLE_COLLISION_TYPE
COLLISION_CONE = 2
G = 9.81  # [m/s^2]


@dataclass(frozen=True)
class ConeParams:
    """Physical cone parameters.

    Attributes:
        small_base: small cone base width [m] (FSG handbook: 228 x 228 mm).
        small_mass: small cone mass [kg] (assumed: a 325 mm rubber-base cone).
        big_base: big cone base width [m] (FSG handbook: 285 x 285 mm).
        big_mass: big cone mass [kg] (assumed: a 505 mm cone).
        mu_ground: cone-asphalt sliding friction coefficient [-] (assumed).
        tip_speed: cone speed after a contact that knocks it "down" [m/s]
            (assumed; a 2D model cannot tip a cone).
        elasticity: restitution of cone contacts [-].
        friction: car-cone contact friction [-].
    """

    small_base: float = 0.228  # [m] REFERENCES.md, FSG handbook (check)
    small_mass: float = 0.6  # [kg] assumed
    big_base: float = 0.285  # [m] REFERENCES.md, FSG handbook (check)
    big_mass: float = 1.6  # [kg] assumed
    mu_ground: float = 0.6  # [-] assumed
    tip_speed: float = 1.0  # [m/s] assumed
    elasticity: float = 0.2  # [-]
    friction: float = 0.5  # [-]

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            low_ok = value >= 0.0 if f.name in ("elasticity", "friction") else value > 0.0
            if not (math.isfinite(value) and low_ok):
                bound = ">= 0" if f.name in ("elasticity", "friction") else "> 0"
                raise ValueError(f"ConeParams.{f.name} must be finite and {bound}, got {value!r}")
        if self.elasticity > 1.0:
            raise ValueError(f"ConeParams.elasticity must be in [0, 1], got {self.elasticity!r}")


def _ground_friction(mu_g: float) -> Any:
    """A pymunk velocity function adding Coulomb ground friction to a cone."""
    decel = mu_g * G

    def velocity_func(body: pymunk.Body, gravity: Any, damping: float, dt: float) -> None:
        pymunk.Body.update_velocity(body, gravity, damping, dt)
        vx, vy = body.velocity
        w = body.angular_velocity
        if vx == 0.0 and vy == 0.0 and w == 0.0:
            return  # at rest: setting a velocity would wake the body and reset its idle time
        speed = math.hypot(vx, vy)
        dv = decel * dt
        if speed <= dv:
            body.velocity = (0.0, 0.0)
        else:
            k = (speed - dv) / speed
            body.velocity = (vx * k, vy * k)
        dw = 4.0 * dv  # spin stops on the same time scale as sliding
        body.angular_velocity = 0.0 if abs(w) <= dw else w - math.copysign(dw, w)

    return velocity_func


class ConeField:
    """All cones of a track as pymunk bodies, with hit and DOO bookkeeping.

    Args:
        space: the pymunk space (its ``sleep_time_threshold`` must be finite
            for idle cones to sleep; ``World`` sets it).
        positions: (n, 2) initial cone positions in `reference` [m].
        kinds: n cone kinds ("blue", "yellow", "orange", "big_orange", "unknown").
        params: physical parameters.
    """

    def __init__(
        self,
        space: pymunk.Space,
        positions: NDArray[np.float64],
        kinds: tuple[str, ...],
        params: ConeParams | None = None,
    ) -> None:
        self.params = params or ConeParams()
        self.initial_positions = np.array(positions, dtype=float).reshape(-1, 2)
        self.initial_positions.setflags(write=False)
        self.kinds = tuple(str(k) for k in kinds)
        if len(self.kinds) != len(self.initial_positions):
            raise ValueError(
                f"ConeField: {len(self.kinds)} kinds for {len(self.initial_positions)} cones"
            )
        self.bodies: list[pymunk.Body] = []
        self._shapes: list[pymunk.Poly] = []
        velocity_func = _ground_friction(self.params.mu_ground)
        for i, (xy, kind) in enumerate(zip(self.initial_positions, self.kinds, strict=True)):
            big = kind == "big_orange"
            mass = self.params.big_mass if big else self.params.small_mass
            base = self.params.big_base if big else self.params.small_base
            body = pymunk.Body(mass, pymunk.moment_for_box(mass, (base, base)))
            body.position = (float(xy[0]), float(xy[1]))
            body.velocity_func = velocity_func
            shape = pymunk.Poly.create_box(body, (base, base))
            shape.collision_type = COLLISION_CONE
            shape.elasticity = self.params.elasticity
            shape.friction = self.params.friction
            shape.cone_id = i
            self.bodies.append(body)
            self._shapes.append(shape)
        self.base_widths = np.array(
            [self.params.big_base if k == "big_orange" else self.params.small_base for k in kinds]
        )
        # Plain-float copies for the per-step bookkeeping (the arrays are the
        # public views; both always hold the same values).
        self._initial_list = [(float(x), float(y)) for x, y in self.initial_positions]
        self._base_widths_list = [float(w) for w in self.base_widths]
        self._join(space)

    def renew(self, space: pymunk.Space) -> None:
        """Move the cones into ``space`` (a new episode's), each back on its mark at rest.

        The field is then as a new ``ConeField(space, positions, kinds, params)``
        is, bit for bit, bookkeeping included, on the same bodies (``sim.bodies``:
        building them is most of a world's reset). A cone that no contact
        touched since the field joined its last space has not moved (only
        contacts move a cone, and each contact starts with a call of a begin
        handler here); the others get their pose, velocities, force and torque
        set again and the solver's bias cleared.
        """
        remove_from_space(self.bodies)
        moved = [self.bodies[i] for i in sorted(self._touched)]
        spend_bias(moved)
        for i in sorted(self._touched):
            body = self.bodies[i]
            body.angle = 0.0
            body.position = self._initial_list[i]
            body.velocity = (0.0, 0.0)
            body.angular_velocity = 0.0
            body.force = (0.0, 0.0)
            body.torque = 0.0
        self._join(space)

    def _join(self, space: pymunk.Space) -> None:
        """Add the cones, as they stand, to ``space``; start the bookkeeping afresh."""
        for body, shape in zip(self.bodies, self._shapes, strict=True):
            space.add(body, shape)
        self._space = space
        self.hit_ids: set[int] = set()
        self.doo_ids: set[int] = set()
        self.hit_events: list[tuple[float, int]] = []
        self.doo_events: list[tuple[float, int]] = []
        self._watch: set[int] = set()
        self._touched: set[int] = set()  # every cone in a contact since joining this space
        self._positions = self.initial_positions.copy()
        self._positions_list = list(self._initial_list)
        self.version = 0  # bumped whenever a cone's position changes
        self.time = 0.0
        space.on_collision(COLLISION_CAR, COLLISION_CONE, begin=self._on_car_contact)
        space.on_collision(COLLISION_CONE, COLLISION_CONE, begin=self._on_cone_contact)

    def sleep_all(self) -> None:
        """Put every resting cone to sleep (call once after adding the car).

        Chipmunk wants bodies that touch asleep together: a cone slept on its
        own while it touches the car, or another cone, corrupts the contact
        memory when it wakes (a crash inside ``Space.step``). So cones whose
        bases touch sleep as one group (``Body.sleep_with_group``), and a
        group that touches the car (a start pose on a cone) stays awake; it
        falls asleep with its neighbours once idle, as Chipmunk groups it.
        """
        for group, touches_car in self.touching_groups():
            if touches_car:
                continue
            first = self.bodies[group[0]]
            if not first.is_sleeping:
                first.sleep()
            for i in group[1:]:
                if not self.bodies[i].is_sleeping:
                    self.bodies[i].sleep_with_group(first)

    def touching_groups(self) -> list[tuple[list[int], bool]]:
        """The cones in groups that touch now (chained), each with whether it
        touches anything else in the space (the car)."""
        n = len(self.bodies)
        rows: list[int] = []
        cols: list[int] = []
        other = np.zeros(n, dtype=bool)
        for i, body in enumerate(self.bodies):
            for shape in body.shapes:
                for hit in self._space.shape_query(shape):
                    j = getattr(hit.shape, "cone_id", None)
                    if j is None:
                        other[i] = True
                    else:
                        rows.append(i)
                        cols.append(j)
        graph = coo_array((np.ones(len(rows)), (rows, cols)), shape=(n, n))
        _, label = connected_components(graph, directed=False)
        groups: dict[int, list[int]] = {}
        for i, g in enumerate(label.tolist()):
            groups.setdefault(g, []).append(i)
        return [(members, bool(other[members].any())) for members in groups.values()]

    def _on_car_contact(self, arbiter: pymunk.Arbiter, space: pymunk.Space, data: Any) -> None:
        for shape in arbiter.shapes:
            cone_id = getattr(shape, "cone_id", None)
            if cone_id is not None:
                self._watch.add(cone_id)
                self._touched.add(cone_id)
                if cone_id not in self.hit_ids:
                    self.hit_ids.add(cone_id)
                    self.hit_events.append((self.time, cone_id))

    def _on_cone_contact(self, arbiter: pymunk.Arbiter, space: pymunk.Space, data: Any) -> None:
        # A cone pushed into another: watch both (not a car hit).
        for shape in arbiter.shapes:
            cone_id = getattr(shape, "cone_id", None)
            if cone_id is not None:
                self._watch.add(cone_id)
                self._touched.add(cone_id)

    def update(self, t: float) -> list[int]:
        """Bookkeeping after a physics step: positions, new DOO cones.

        Only cones touched since they last slept are inspected, so the cost
        does not grow with the track.

        Args:
            t: simulation time after the step [s].

        Returns:
            Ids of cones that became down-or-out at this step.
        """
        self.time = t
        if not self._watch:
            return []
        new_doo: list[int] = []
        settled: list[int] = []
        positions = self._positions_list
        for i in sorted(self._watch):
            body = self.bodies[i]
            x, y = body.position
            px, py = positions[i]
            if x != px or y != py:
                positions[i] = (x, y)
                self._positions[i] = (x, y)
                self.version += 1
                px, py = x, y
            if i not in self.doo_ids:
                # Out: the whole base has left its marked square (axis-aligned
                # at the cone's start), i.e. moved a full base width along x or y.
                x0, y0 = self._initial_list[i]
                dx, dy = px - x0, py - y0
                out = max(abs(dx), abs(dy)) > self._base_widths_list[i]
                if out or body.velocity.length > self.params.tip_speed:
                    self.doo_ids.add(i)
                    self.doo_events.append((t, i))
                    new_doo.append(i)
            if body.is_sleeping:
                settled.append(i)
        self._watch.difference_update(settled)
        return new_doo

    @property
    def positions(self) -> NDArray[np.float64]:
        """(n, 2) current cone positions in `reference` [m] (read-only view)."""
        view = self._positions.view()
        view.setflags(write=False)
        return view

    @property
    def awake_count(self) -> int:
        """Number of cones pymunk is integrating now."""
        return sum(1 for b in self.bodies if not b.is_sleeping)
