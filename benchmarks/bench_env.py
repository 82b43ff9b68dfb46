"""The closed loop's speed and the autopilot's lap time.

Prints (timing never decides a test):

1. env steps per second with a random policy (``ideal`` and ``rtk`` sensors,
   ``fused`` localization), and in the same run the time spent in the bare
   physics it contains (``World`` steps minus sensors), so the overhead of
   the env, the sensors and localization is visible;
2. the real-time factor of ``conesim run``'s loop on autocross, full stack
   (sensors, EKF, planner, control), one core;
3. the autopilot's best lap against the friction-limited lap time along the
   true centreline, on every closed track.

Run: ``.venv/bin/python benchmarks/bench_env.py``.
"""

from __future__ import annotations

import time

import numpy as np

from envs.cone_track_env import ConeTrackEnv
from envs.runner import run_scenario

STEPS = 1500


def env_rate(sensors: str) -> tuple[float, float, float]:
    """(env steps/s, fraction of time in physics, fraction in World.step)."""
    env = ConeTrackEnv(track="autocross", sensors=sensors, terminate_off_track=False)
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    t0 = time.perf_counter()
    for _ in range(STEPS):
        env.step(rng.uniform(-0.3, 1.0, 2).astype(np.float32))
    total = time.perf_counter() - t0
    n = STEPS * env.config.substeps
    # The bare physics of as many steps (car and cones, no sensors, no race
    # control), then whole World steps (physics, race control, sensors).
    env.reset(seed=0)
    world = env.stack.world
    t0 = time.perf_counter()
    for _ in range(n):
        world.vehicle.pre_step(world.dt)
        world.space.step(world.dt)
        world.vehicle.post_step()
    physics = time.perf_counter() - t0
    env.reset(seed=0)
    world = env.stack.world
    t0 = time.perf_counter()
    for _ in range(n):
        world.step()
    world_time = time.perf_counter() - t0
    return STEPS / total, physics / total, world_time / total


def main() -> None:
    """Print the figures."""
    print(f"env steps/s with a random policy, autocross, {STEPS} steps of 4 physics substeps")
    for sensors in ("ideal", "rtk"):
        rate, phys, world = env_rate(sensors)
        print(
            f"  {sensors:5s} sensors, fused: {rate:7.0f} steps/s; bare physics {100 * phys:4.1f} % "
            f"of the time (env / physics = {1 / phys:4.1f}x), World.step incl. sensors "
            f"{100 * world:4.1f} %"
        )
    print("closed loop (conesim run), autocross, 2 laps, rtk, fused, seed 0:")
    r = run_scenario("autocross", laps=2, seed=0)
    print(
        f"  {r.sim_time_s:.1f} s simulated in {r.wall_time_s:.2f} s wall: "
        f"{r.real_time_factor:.1f}x real time"
    )
    print("autopilot best lap against the friction-limited lap (QSS, true centreline):")
    for track in ("trackdrive", "autocross", "skidpad", "acceleration"):
        r = run_scenario(track, laps=2, seed=0)
        best = "n/a" if r.best_lap_s is None else f"{r.best_lap_s:6.2f} s"
        ratio = "n/a" if r.lap_time_ratio is None else f"{r.lap_time_ratio:4.2f}x"
        print(
            f"  {track:12s} best {best}  limit {r.limit_lap_time_s:6.2f} s  ratio {ratio}"
            f"  cones hit {r.cones_hit}"
        )


if __name__ == "__main__":
    main()
