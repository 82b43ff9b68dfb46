"""Speed of the frame tree on spec 000's chain reference -> gps_antenna -> os_sensor.

Prints CPU microseconds per call (``time.process_time``, so other work on a
shared machine does not count), the median over repeats of ``timeit`` runs, for:
one lookup at an interpolated time and at time 0 (latest common time), one
inverse lookup, the time-travel lookup ``lookup_transform_full`` (os_sensor
at one time into os_sensor 1 s later through reference, two interpolated
legs) and its 50-point ``transform_points_full`` (beside the same done by
hand with two ``transform_points`` calls), transforming 50 points,
``lookup_pose2d``, and
``set_transform`` of one dynamic transform into a link whose 10 s cache is
full (so every insert also prunes one sample). Run: ``python benchmarks/bench_frames.py``.
"""

from __future__ import annotations

import math
import statistics
import time
import timeit
from collections.abc import Callable, Iterator

import numpy as np

from conesim.core.pose import Pose2D
from conesim.localization.frames import LATEST, Buffer, TransformStamped

RATE = 20.0  # dynamic link rate [Hz], as the ROS pipeline's broadcaster
HISTORY = 10.0  # sim time already held when measuring [s]
REPEATS = 7
NUMBER = 20_000


def vehicle_transform(stamp: float) -> TransformStamped:
    """The vehicle driving a 20 m circle at 5 m/s, as reference -> gps_antenna at ``stamp`` [s]."""
    angle = 0.25 * stamp
    pose = Pose2D(20.0 * math.cos(angle), 20.0 * math.sin(angle), angle + math.pi / 2)
    return TransformStamped.from_pose2d("reference", "gps_antenna", stamp, pose)


def seed_buffer() -> Buffer:
    """Spec 000's tree with HISTORY seconds of the dynamic link at RATE."""
    buffer = Buffer()
    for k in range(int(HISTORY * RATE) + 1):
        buffer.set_transform(vehicle_transform(k / RATE))
    buffer.set_transform_static(
        TransformStamped("gps_antenna", "os_sensor", 0.0, translation=(0.0, 0.0, -0.1))
    )
    return buffer


def median_us(call: Callable[[], object], number: int = NUMBER) -> float:
    """Median over REPEATS runs of the CPU time per call [us]."""
    runs = timeit.repeat(call, number=number, repeat=REPEATS, timer=time.process_time)
    return statistics.median(runs) / number * 1e6


def _inserter(buffer: Buffer, transforms: Iterator[TransformStamped]) -> Callable[[], bool]:
    """A call that inserts the next transform."""
    return lambda: buffer.set_transform(next(transforms))


def bench_set_transform() -> float:
    """Median time per set_transform into a full 10 s cache [us]."""
    number = 2_000
    runs = []
    for _ in range(REPEATS):
        buffer = seed_buffer()
        transforms = [vehicle_transform(HISTORY + (k + 1) / RATE) for k in range(number)]
        insert = _inserter(buffer, iter(transforms))
        runs.append(timeit.timeit(insert, number=number, timer=time.process_time))
    return statistics.median(runs) / number * 1e6


def main() -> None:
    """Run each case and print one line per case."""
    buffer = seed_buffer()
    between = HISTORY / 2 + 0.5 / RATE  # half-way between two stamps [s]
    points = np.random.default_rng(0).uniform(-20.0, 20.0, (50, 3))
    cases: list[tuple[str, Callable[[], object]]] = [
        (
            "lookup reference<-os_sensor, interpolated time",
            lambda: buffer.lookup_transform("reference", "os_sensor", between),
        ),
        (
            "lookup reference<-os_sensor, time 0 (latest)",
            lambda: buffer.lookup_transform("reference", "os_sensor", LATEST),
        ),
        (
            "lookup os_sensor<-reference, interpolated time",
            lambda: buffer.lookup_transform("os_sensor", "reference", between),
        ),
        (
            "lookup_transform_full os_sensor 1 s back, interp.",
            lambda: buffer.lookup_transform_full(
                "os_sensor", between, "os_sensor", between - 1.0, "reference"
            ),
        ),
        (
            "transform_points_full 50 x (n, 2), 1 s back",
            lambda: buffer.transform_points_full(
                "os_sensor", between, "os_sensor", points[:, :2], between - 1.0, "reference"
            ),
        ),
        (
            "the same as 2 transform_points via reference",
            lambda: buffer.transform_points(
                "os_sensor",
                "reference",
                buffer.transform_points("reference", "os_sensor", points[:, :2], between - 1.0),
                between,
            ),
        ),
        (
            "transform_points 50 x (n, 3), interpolated time",
            lambda: buffer.transform_points("reference", "os_sensor", points, between),
        ),
        (
            "transform_points 50 x (n, 2), time 0",
            lambda: buffer.transform_points("reference", "os_sensor", points[:, :2], LATEST),
        ),
        (
            "lookup_pose2d reference<-os_sensor, interpolated",
            lambda: buffer.lookup_pose2d("reference", "os_sensor", between),
        ),
        (
            "TransformStamped.from_pose2d",
            lambda: vehicle_transform(between),
        ),
    ]
    print(f"frame tree, median of {REPEATS} repeats [CPU us per call]")
    for name, call in cases:
        print(f"  {name:<50s} {median_us(call):8.2f}")
    print(f"  {'set_transform, dynamic, full 10 s cache':<50s} {bench_set_transform():8.2f}")


if __name__ == "__main__":
    main()
