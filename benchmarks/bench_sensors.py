"""Cost of the sensor models: the whole rtk suite per simulated second, and the
cone detector per scan with 300 and 1,000 cones on the track.

A synthetic truth drives a circle at 10 m/s between two rings of cones (inner
and outer radius = centre radius -+ 2 m, 1.25 m cone spacing per ring), so the
number of cones in the detector's 15 m range stays ~40 whatever the track
length. Plain script; prints figures, asserts nothing.

    .venv/bin/python benchmarks/bench_sensors.py
"""

from __future__ import annotations

import math
import statistics
import time
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from conesim.core.pose import Pose2D
from conesim.sim.sensors import ConeDetector, ConeMap, SensorSuite, TruthSample, get_profile
from conesim.sim.sensors.suite import Sensor

PHYSICS_HZ = 200.0
SPEED = 10.0  # [m/s]


def circle_track(n_cones: int) -> tuple[float, np.ndarray, tuple[str, ...]]:
    """Centre radius [m], (n, 2) cones and kinds of a two-ring track with n cones."""
    per_ring = n_cones // 2
    radius = per_ring * 1.25 / (2 * math.pi)
    a = np.linspace(0.0, 2 * math.pi, per_ring, endpoint=False)
    ring = np.column_stack([np.cos(a), np.sin(a)])
    cones = np.vstack([(radius - 2.0) * ring, (radius + 2.0) * ring])
    return radius, cones, ("blue",) * per_ring + ("yellow",) * per_ring


def truths(
    seconds: float, radius: float, cones: np.ndarray, kinds: tuple[str, ...], cmap: ConeMap | None
) -> list[TruthSample]:
    """Truth at every physics step of ``seconds`` of driving the circle."""
    out = []
    for k in range(round(seconds * PHYSICS_HZ)):
        t = k / PHYSICS_HZ
        th = SPEED * t / radius
        pose = Pose2D(radius * math.cos(th), radius * math.sin(th), th + math.pi / 2)
        out.append(
            TruthSample(t, pose, SPEED, SPEED / radius, 0.0, SPEED**2 / radius, cones, kinds, cmap)
        )
    return out


def best_of(repeats: int, fn: Callable[[], object]) -> tuple[float, float]:
    """(median, min) wall time of ``fn`` [s] over ``repeats`` runs."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times), min(times)


def bench_suite(seconds: float = 10.0) -> None:
    """The rtk suite driven at 200 Hz, per simulated second."""
    radius, cones, kinds = circle_track(300)
    for label, cmap in (("with ConeMap", ConeMap(cones, kinds)), ("full search", None)):
        samples = truths(seconds, radius, cones, kinds, cmap)
        counts: list[int] = []

        def run(samples: list[TruthSample] = samples, counts: list[int] = counts) -> None:
            suite = SensorSuite("rtk", seed=0)
            counts[:] = [sum(len(suite.step(tr)) for tr in samples)]

        med, low = best_of(5, run)
        per_s = med / seconds
        print(
            f"rtk suite, 300 cones, {label:12s}: {per_s * 1e3:6.2f} ms per simulated s "
            f"(min {low / seconds * 1e3:.2f}), {counts[0] / seconds:.0f} messages/s, "
            f"{1.0 / per_s:.0f}x real time (sensors alone)"
        )


def bench_per_sensor(seconds: float = 10.0) -> None:
    """Each sensor's capture cost, called directly at its own rate."""
    radius, cones, kinds = circle_track(300)
    samples = truths(seconds, radius, cones, kinds, ConeMap(cones, kinds))
    suite = SensorSuite("rtk", seed=0)
    for sensor in (suite.gps, suite.heading, suite.imu, suite.wheel_speed, suite.cones):
        chosen = samples[:: round(PHYSICS_HZ / sensor.config.rate)]

        def run(sensor: Sensor = sensor, chosen: list[TruthSample] = chosen) -> None:
            sensor.reset(0)
            for truth in chosen:
                sensor.capture(truth)

        med, _ = best_of(5, run)
        print(f"  {sensor.name:11s} {med / len(chosen) * 1e6:7.1f} us per capture")


def bench_detector() -> None:
    """The rtk cone detector per scan, 300 and 1,000 cones, with and without a ConeMap."""
    detector = ConeDetector(get_profile("rtk").cones, seed=0)
    for n in (300, 1000):
        radius, cones, kinds = circle_track(n)
        cmap = ConeMap(cones, kinds)
        with_map = truths(10.0, radius, cones, kinds, cmap)[::20]
        plain = [replace(s, cone_map=None) for s in with_map]
        seen = np.mean([len(detector.capture(s)) for s in with_map])
        for label, batch in (("ConeMap", with_map), ("full search", plain)):

            def scan_all(batch: list[TruthSample] = batch) -> None:
                for truth in batch:
                    detector.capture(truth)

            med, _ = best_of(7, scan_all)
            print(
                f"cone detector, {n:5d} cones on a {2 * math.pi * radius:4.0f} m track, "
                f"{label:11s}: {med / len(batch) * 1e6:6.1f} us per scan ({seen:.0f} detections)"
            )

        def update_all(cmap: ConeMap = cmap, cones: np.ndarray = cones) -> None:
            for _ in range(200):
                cmap.update(cones)

        med, _ = best_of(7, update_all)
        print(f"  ConeMap.update (no cone moved), {n} cones: {med / 200 * 1e6:.1f} us per step")


if __name__ == "__main__":
    bench_suite()
    bench_per_sensor()
    bench_detector()
