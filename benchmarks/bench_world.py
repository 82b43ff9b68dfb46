"""Physics with cones, and the whole simulated world, per simulated second.

Prints (timing never decides a test, STYLE.md):

1. physics steps per second of the car alone, and with 300 and 1,000 cones
   on the ground (the issue's target: cones add under 20 % to the car alone);
2. the cost of ``World.step`` on the autocross track with the ``rtk`` sensor
   suite, split into physics + race control and sensors.

Run: ``.venv/bin/python benchmarks/bench_world.py``.
"""

from __future__ import annotations

import math
import time

import numpy as np
import pymunk

from conesim.core.pose import Pose2D
from conesim.sim.cones import ConeField
from conesim.sim.vehicle import Vehicle, step
from conesim.sim.vehicle_params import VehicleParams
from conesim.sim.world import IDLE_SPEED_THRESHOLD, SLEEP_TIME_THRESHOLD, World, WorldConfig
from conesim.tracks import load_track

DT = 1.0 / 200.0  # [s]
STEPS = 10_000  # 50 s simulated
REPEATS = 5


def physics_rate(n_cones: int) -> float:
    """Steps per second of a car doing a slalom beside ``n_cones`` idle cones."""
    space = pymunk.Space()
    space.sleep_time_threshold = SLEEP_TIME_THRESHOLD
    space.idle_speed_threshold = IDLE_SPEED_THRESHOLD
    car = Vehicle(space, VehicleParams(), Pose2D(0.0, 0.0, 0.0), speed=12.0)
    if n_cones:
        # Two lines of cones 3 m apart on both sides of a 600 m lane, as a track has.
        x = np.repeat(np.linspace(-50.0, 550.0, n_cones // 2), 2)
        y = np.tile([-25.0, 25.0], n_cones // 2)
        cones = ConeField(space, np.column_stack([x, y]), ("blue",) * len(x))
        space.step(1e-9)
        cones.sleep_all()
    t0 = time.perf_counter()
    for i in range(STEPS):
        s = car.state
        car.set_command(0.1 * math.sin(0.5 * i * DT), 1.0 * (12.0 - s.vx))
        step(space, car, DT)
    return STEPS / (time.perf_counter() - t0)


def world_cost(sensors: str) -> tuple[float, float]:
    """Microseconds per World.step on autocross, with and without the sensors."""
    track = load_track("autocross")
    results = []
    for enabled in (True, False):
        world = World(track, WorldConfig(sensors=sensors), seed=0)
        if not enabled:
            for name in ("gps", "heading", "imu", "wheel_speed", "cones"):
                world.sensors.set_enabled(name, False)
        world.set_command(0.0, 1.0)
        t0 = time.perf_counter()
        for _ in range(2000):
            world.step()
        results.append((time.perf_counter() - t0) / 2000 * 1e6)
    return results[0], results[1]


def main() -> None:
    """Print the figures."""
    print(f"physics at dt = {DT} s, {STEPS} steps, best of {REPEATS}")
    base = 0.0
    for n in (0, 300, 1000):
        rate = max(physics_rate(n) for _ in range(REPEATS))
        base = base or rate
        extra = (base / rate - 1.0) * 100.0
        us = 1e6 / rate
        print(f"  car + {n:5d} cones  {rate:10,.0f} steps/s  {us:6.1f} us/step  +{extra:4.1f} %")
    for sensors in ("rtk", "ideal"):
        with_s, without = min(world_cost(sensors) for _ in range(3))
        per_sim_s = 200.0 * with_s / 1000.0
        print(
            f"World.step autocross, {sensors:5s} sensors: {with_s:6.1f} us/step "
            f"({without:5.1f} physics + race control, {with_s - without:5.1f} sensors) "
            f"= {per_sim_s:5.1f} ms per simulated s, {1000.0 / per_sim_s:5.0f}x real time"
        )


if __name__ == "__main__":
    main()
