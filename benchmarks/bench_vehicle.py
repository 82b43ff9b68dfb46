"""Physics steps per second of the car alone in a pymunk space at 200 Hz.

Prints figures; timing never decides a test (STYLE.md). Run:
``.venv/bin/python benchmarks/bench_vehicle.py``.
"""

from __future__ import annotations

import math
import time

import pymunk

from conesim.core.pose import Pose2D
from conesim.sim.vehicle import Vehicle, step
from conesim.sim.vehicle_params import VehicleParams

DT = 1.0 / 200.0  # [s]
STEPS = 20_000  # 100 s of simulated time
REPEATS = 5


def run_once(initial_speed: float, manoeuvre: str) -> float:
    """Steps per second [1/s] of one run of STEPS steps."""
    space = pymunk.Space()
    car = Vehicle(space, VehicleParams(), Pose2D(0.0, 0.0, 0.0), speed=initial_speed)
    t0 = time.perf_counter()
    for i in range(STEPS):
        if manoeuvre == "slalom":
            s = car.state
            car.set_command(0.1 * math.sin(0.5 * i * DT), 1.0 * (12.0 - s.vx))
        step(space, car, DT)
    return STEPS / (time.perf_counter() - t0)


def main() -> None:
    """Print the best-of-REPEATS rate for a few regimes."""
    print(f"conesim car alone, dt = {DT} s, {STEPS} steps, best of {REPEATS}")
    for label, speed, manoeuvre in (
        ("at rest (kinematic model)", 0.0, "hold"),
        ("coasting at 12 m/s (dynamic model)", 12.0, "coast"),
        ("slalom + speed control at 12 m/s (with state/command)", 12.0, "slalom"),
    ):
        rate = max(run_once(speed, manoeuvre) for _ in range(REPEATS))
        print(
            f"  {label:55s} {rate:10,.0f} steps/s  {1e6 / rate:6.1f} us/step  {rate * DT:6.0f}x RT"
        )


if __name__ == "__main__":
    main()
