"""The env's speed, layer by layer, the closed loop's and the autopilot's lap time.

Prints (timing never decides a test):

0. the machine's speed now: bare pymunk steps per second (one box, no
   contacts: ``timing.pymunk_reference``, as ``write_results``), before and after section 1;
1. env steps per second with a random policy on autocross, for truth
   localization with ideal sensors and for the default configuration (rtk,
   fused), the time inside the closed loop (``ClosedLoop.step``:
   localization and the frame tree) timed within that run, then the same
   commands replayed through each layer below alone: ``World.step``
   (sensors, race control), the car model and pymunk (``Vehicle.pre_step`` /
   ``post_step`` and ``Space.step``) and pymunk's ``Space.step`` alone, so
   that the time per env step splits into the layers' shares;
2. the real-time factor of ``conesim run``'s loop on autocross, full stack
   (sensors, EKF, planner, control), one core;
3. the autopilot's best lap against the friction-limited lap time along the
   true centreline, on every closed track;
4. the floor filterpy's EKF sets: the time spent inside filterpy's own
   ``ExtendedKalmanFilter.predict`` and ``update`` calls during section 1's
   rtk/fused run (the design card names filterpy's EKF; these calls are its
   numpy code, not ours), per env step and per simulated second, and the
   ceilings that time alone puts on the figures of issue 6 with everything
   else (physics, sensors, planner, our own EKF code) taken as free;
5. vector envs: env steps per second (wall clock) of one env against
   ``gymnasium.make_vec`` with 2 async workers, in turn, beside the
   machine's own scaling measured in the same run (two bare Python
   processes at once against one: the ratio means something only against it).

Sections 1 and 4 time CPU time (``time.process_time``), so that another
process on a busy machine does not inflate them; sections 2 and 5 report
wall time.

Run: ``.venv/bin/python benchmarks/bench_env.py [--sections 0,1,2,3,4,5]``.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from filterpy.kalman import ExtendedKalmanFilter

from conesim import ENV_ID
from conesim.envs.cone_track_env import ConeTrackEnv
from conesim.envs.loop import StepRecord
from conesim.envs.runner import run_scenario
from conesim.planner.messages import ControlCommand

from timing import pymunk_reference, timed_calls, two_process_scaling

STEPS = 1500
LAYERS = ("env", "loop", "World.step", "car + pymunk", "pymunk")
# (label, env keywords, issue 17's target [env steps/s] or None)
CONFIGS: tuple[tuple[str, dict[str, Any], int | None], ...] = (
    ("ideal sensors, truth", {"sensors": "ideal", "localization": "truth"}, 10_000),
    ("rtk sensors, fused (default)", {}, 4_000),
    # What the design's 200 Hz physics (4 steps per action) costs: half of them.
    (
        "ideal sensors, truth, physics 100 Hz",
        {"sensors": "ideal", "localization": "truth", "physics_rate": 100.0},
        None,
    ),
    # What the training baseline's path preview adds to the env layer.
    (
        "ideal sensors, truth, path preview 10 x 3 m",
        {"sensors": "ideal", "localization": "truth", "path_preview": 10, "path_preview_step": 3.0},
        None,
    ),
)
VEC_TARGET = 1.6  # issue 17: 2 workers on 2 cores give at least this times one env
REPEATS = 3  # rounds of the layers in ``layer_rates``


def layer_rates(repeats: int = REPEATS, **kwargs: Any) -> dict[str, float]:
    """Env steps/s of each layer alone on the same random commands (CPU time).

    The layers run in turn, ``repeats`` rounds of them all, and each layer's
    median round is taken: a busy machine's drift hits every layer alike.
    """
    env = ConeTrackEnv(track="autocross", terminate_off_track=False, **kwargs)
    rng = np.random.default_rng(0)
    actions = [rng.uniform(-0.3, 1.0, 2).astype(np.float32) for _ in range(STEPS)]
    commands = [env.action_to_command(a) for a in actions]
    substeps = env.config.substeps

    def run_env() -> None:
        # The loop's share is timed inside the env's run: a replay of its own
        # drifts with the machine as much as the share it would measure.
        loop_step = env.loop.step
        inner = 0.0

        def timed(command: ControlCommand | None = None) -> StepRecord:
            nonlocal inner
            t0 = time.process_time()
            try:
                return loop_step(command)
            finally:
                inner += time.process_time() - t0

        env.loop.step = timed  # type: ignore[method-assign]
        try:
            for action in actions:
                env.step(action)
        finally:
            del env.loop.step
        spent["loop"].append(inner)

    def run_world() -> None:
        world = env.loop.world
        for steer, accel in commands:
            world.set_command(steer, accel)
            for _ in range(substeps):
                world.step()

    def run_physics() -> None:
        world = env.loop.world
        vehicle, space, h = world.vehicle, world.space, world.dt
        for steer, accel in commands:
            vehicle.set_command(steer, accel)
            for _ in range(substeps):
                vehicle.pre_step(h)
                space.step(h)
                vehicle.post_step()
        # pymunk alone, as often, on the space the car's drive left behind
        t0 = time.process_time()
        for _ in range(STEPS * substeps):
            space.step(h)
        spent["pymunk"].append(time.process_time() - t0)

    spent: dict[str, list[float]] = {name: [] for name in LAYERS}
    for _ in range(repeats):
        layers = (("env", run_env), ("World.step", run_world), ("car + pymunk", run_physics))
        for name, run in layers:
            env.reset(seed=0)
            t0 = time.process_time()
            run()
            took = time.process_time() - t0
            # run_physics timed pymunk alone after the car: that part is not the car's
            spent[name].append(took - (spent["pymunk"][-1] if name == "car + pymunk" else 0.0))
    return {name: STEPS / float(np.median(times)) for name, times in spent.items()}


def speed_by_layer() -> None:
    """Section 1: env steps/s and the share of each layer."""
    print(f"env steps/s with a random policy, autocross, {STEPS} steps at 50 Hz")
    print("  (each layer alone on the same commands; us per env step below it)")
    for label, kwargs, target in CONFIGS:
        rates = layer_rates(**kwargs)
        cost = [1e6 / rates[name] for name in LAYERS]
        shares = [a - b for a, b in zip(cost, [*cost[1:], 0.0], strict=True)]
        aim = "" if target is None else f" (issue 17's target {target:,} steps/s)"
        print(f"  {label}: {rates['env']:,.0f} steps/s{aim}")
        print("    " + ", ".join(f"{name} {rates[name]:,.0f}/s" for name in LAYERS[1:]))
        names = ("env layer", "localization + loop", "sensors + race control", "car model",
                 "pymunk")  # fmt: skip
        print(
            f"    per env step {cost[0]:.0f} us: "
            + ", ".join(
                f"{n} {c:.0f} ({100 * c / cost[0]:.0f} %)"
                for n, c in zip(names, shares, strict=True)
            )
        )


def main() -> None:
    """Print the figures."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sections", default="0,1,2,3,4,5", help="comma-separated: 0 to 5")
    args = parser.parse_args()
    sections = {s.strip() for s in args.sections.split(",")}
    if "0" in sections:
        print(f"reference, bare pymunk (one box, no contacts): {pymunk_reference():,.0f} steps/s")
    if "1" in sections:
        speed_by_layer()
    if "0" in sections:
        print(f"reference again, bare pymunk: {pymunk_reference():,.0f} steps/s")
    if "2" in sections:
        closed_loop()
    if "3" in sections:
        lap_ratios()
    if "4" in sections:
        filterpy_floor()
    if "5" in sections:
        vector_scaling()


def _cpu_seconds(pid: int) -> float:
    """A live process's user + system CPU time [s] (Linux ``/proc``)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _one_env(actions: np.ndarray) -> tuple[float, float]:
    """One env over ``actions``: (wall steps/s, CPU s per step)."""
    env = gym.make(ENV_ID, track="autocross", terminate_off_track=False)
    env.reset(seed=0)
    t0, c0 = time.perf_counter(), time.process_time()
    for action in actions[:, 0]:
        _, _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            env.reset()
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    env.close()
    return len(actions) / wall, cpu / len(actions)


def _two_workers(actions: np.ndarray) -> tuple[float, float, float]:
    """``make_vec`` with 2 async workers over ``actions``: (wall env steps/s,
    workers' CPU s per env step, the main process's CPU s per vec step)."""
    vec = gym.make_vec(
        ENV_ID, num_envs=2, vectorization_mode="async", track="autocross", terminate_off_track=False
    )
    vec.reset(seed=0)
    vec.step(actions[0])  # the workers are up
    pids = [p.pid for p in vec.unwrapped.processes]  # type: ignore[attr-defined]
    w0 = sum(_cpu_seconds(pid) for pid in pids)
    t0, c0 = time.perf_counter(), time.process_time()
    for action in actions:
        vec.step(action)
    wall, main_cpu = time.perf_counter() - t0, time.process_time() - c0
    workers = sum(_cpu_seconds(pid) for pid in pids) - w0
    vec.close()
    steps = len(actions)
    return 2 * steps / wall, workers / (2 * steps), main_cpu / steps


def vector_scaling(steps: int = 1000, rounds: int = 3) -> None:
    """Section 5: one env against two async workers, wall clock and CPU time.

    One env and the vector env run in turn, ``rounds`` times, and each
    figure is the median round's; the ratio is taken round by round, beside
    the machine's own two-process scaling measured just before (no vector
    env scales better than two bare processes do). The CPU time of the
    workers (from ``/proc``, over the timed steps only) and of the main
    process per env step, against one env's, says what the vector env costs
    beside the env itself, whatever the load.
    """
    print(f"vector envs, default configuration, {steps} steps per env, median of {rounds} rounds:")
    machine = two_process_scaling()
    rng = np.random.default_rng(0)
    actions = rng.uniform(-0.3, 1.0, (steps, 2, 2)).astype(np.float32)
    ones, twos = [], []
    for _ in range(rounds):
        ones.append(_one_env(actions))
        twos.append(_two_workers(actions))
    ratio = float(np.median([b[0] / a[0] for a, b in zip(ones, twos, strict=True)]))
    one, one_cpu = (float(np.median(v)) for v in zip(*ones, strict=True))
    two, worker, main = (float(np.median(v)) for v in zip(*twos, strict=True))
    load = ", ".join(f"{v:.1f}" for v in os.getloadavg())
    # On two idle cores the workers step side by side, then the main process
    # gathers their results while they wait: a vec step takes worker + main.
    idle = 2.0 * one_cpu / (worker + main)
    print(
        f"  wall clock: 1 env {one:,.0f} steps/s; 2 async workers {two:,.0f} steps/s:"
        f" {ratio:.2f}x (issue 17's target {VEC_TARGET}x; load average {load} on"
        f" {os.cpu_count()} cores)"
        f"\n  the machine now: two bare Python processes at once {machine:.2f}x one"
        f" (2.00x on two idle cores); the vector env gets {ratio / machine:.0%} of that"
        f"\n  CPU: 1 env {1e6 * one_cpu:.0f} us per step; 2 async workers"
        f" {1e6 * worker:.0f} us per env step each, the main process {1e6 * main:.0f} us"
        f" per vec step: on 2 idle cores 2 x {1e6 * one_cpu:.0f} /"
        f" ({1e6 * worker:.0f} + {1e6 * main:.0f}) = {idle:.2f}x"
    )


def closed_loop() -> None:
    """Section 2: the real-time factor of ``conesim run``."""
    print("closed loop (conesim run), autocross, 2 laps, rtk, fused, seed 0:")
    r = run_scenario("autocross", laps=2, seed=0)
    print(
        f"  {r.sim_time_s:.1f} s simulated in {r.wall_time_s:.2f} s wall: "
        f"{r.real_time_factor:.1f}x real time (setup {r.setup_time_s:.2f} s before it, apart)"
    )


def lap_ratios() -> None:
    """Section 3: best lap against the friction-limited lap."""
    print("autopilot best lap against the friction-limited lap (QSS, true centreline):")
    for track in ("trackdrive", "autocross", "skidpad", "acceleration"):
        r = run_scenario(track, laps=2, seed=0)
        best = "n/a" if r.best_lap_s is None else f"{r.best_lap_s:6.2f} s"
        ratio = "n/a" if r.lap_time_ratio is None else f"{r.lap_time_ratio:4.2f}x"
        print(
            f"  {track:12s} best {best}  limit {r.limit_lap_time_s:6.2f} s  ratio {ratio}"
            f"  cones hit {r.cones_hit}"
        )


def filterpy_floor() -> None:
    """Section 4: filterpy's own time in the loop and the ceilings it alone sets.

    Issue 6 asks for env / physics <= 2 (so physics P >= filterpy F per step)
    and >= 5,000 steps/s (P + F <= 200 us): together F <= 100 us per step.
    A lower bound on the calls of any filter fed these messages: one predict
    per IMU sample and one update per heading, wheel speed and GPS message
    (this one also predicts to each update's stamp, off the IMU's grid, and
    replays late fixes); that count at the measured cost per call is printed.
    """
    targets = [(ExtendedKalmanFilter, "predict"), (ExtendedKalmanFilter, "update")]
    with timed_calls(targets, time.process_time) as tally:
        rates = layer_rates()
    rate = rates["env"]
    steps = REPEATS * STEPS  # the env's run is timed in every round
    calls = tally["predict"] + tally["update"]
    per_step = tally["time"] / steps  # [s] filterpy per env step
    per_call = tally["time"] / calls
    physics_per_step = 1.0 / rates["car + pymunk"]  # [s] bare physics per env step
    env = ConeTrackEnv(track="autocross")
    control_rate = env.config.control_rate
    profile = env.loop.world_config.sensor_profile
    least_calls = (
        profile.imu.rate + profile.heading.rate + profile.wheel_speed.rate + profile.gps.rate
    ) / control_rate
    least = least_calls * per_call
    print(
        "filterpy's own EKF calls (predict, update) in the env, rtk, fused, autocross:"
        f"\n  {tally['predict'] / steps:.1f} predicts + {tally['update'] / steps:.1f} updates"
        f" per env step, {1e6 * per_call:.0f} us per call: {1e6 * per_step:.0f} us per env"
        f" step ({1e3 * per_step * control_rate:.1f} ms per simulated second),"
        f" {100 * per_step * rate:.1f} % of the env's time"
        "\n  ceilings with everything else free: env"
        f" {1 / per_step:,.0f} steps/s (target 5,000); env / physics"
        f" >= {1 + per_step / physics_per_step:.1f}x (target 2x, physics"
        f" {1e6 * physics_per_step:.0f} us per step); real time factor"
        f" {1 / (per_step * control_rate):.0f}x (target 100x)"
        f"\n  with the bare physics as it is, everything else free: env"
        f" {1 / (per_step + physics_per_step):,.0f} steps/s, real time factor"
        f" {1 / ((per_step + physics_per_step) * control_rate):.0f}x"
        f"\n  at least one call per message: {least_calls:.1f} per env step,"
        f" {1e6 * least:.0f} us (env / physics >= {1 + least / physics_per_step:.1f}x);"
        " issue 6's steps/s and ratio together allow <= 100 us"
    )


if __name__ == "__main__":
    main()
