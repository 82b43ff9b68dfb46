"""Time a library's own calls inside a run, and the machine's speed: shared by the benchmarks.

``timed_calls`` swaps attributes (methods of a class, functions a module
imported) for wrappers that add each call's time to a tally, and puts the
originals back on exit. The benchmarks use it to show the floor that a
library the design card names sets (filterpy's EKF in ``bench_env``,
scipy's Delaunay and splprep in ``bench_planner``), measured in the real
run, on its real data, with its real cache state. ``pymunk_reference`` is
the machine's speed, measured beside a figure (``write_results``, ``bench_env``);
``two_process_scaling`` is how far two processes scale on it now (``bench_env``).
"""

from __future__ import annotations

import multiprocessing
import statistics
import time
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from typing import Any

import pymunk


@contextmanager
def timed_calls(
    targets: Iterable[tuple[object, str]], clock: Callable[[], float] = time.perf_counter
) -> Iterator[dict[str, float]]:
    """Accumulate the time [s] and the count of calls to ``owner.name`` for each target.

    Yields a dict with ``time`` (all targets together), and per name its
    calls and ``<name>_time`` [s], updated as the calls happen; the
    attributes are put back on exit, also after an error.
    """
    tally: dict[str, float] = {"time": 0.0}
    originals = [(owner, name, getattr(owner, name)) for owner, name in targets]

    def timed(name: str, function: Callable[..., Any]) -> Callable[..., Any]:
        def call(*args: Any, **kwargs: Any) -> Any:
            t0 = clock()
            try:
                return function(*args, **kwargs)
            finally:
                spent = clock() - t0
                tally["time"] += spent
                tally[f"{name}_time"] += spent
                tally[name] += 1

        return call

    try:
        for owner, name, function in originals:
            tally[name] = 0
            tally[f"{name}_time"] = 0.0
            setattr(owner, name, timed(name, function))
        yield tally
    finally:
        for owner, name, function in originals:
            setattr(owner, name, function)


REFERENCE_STEPS = 50_000


def pymunk_reference() -> float:
    """Bare pymunk steps per second: one 1 kg box, 200 Hz steps, no contacts.

    The machine's speed at the moment, measured beside a figure so that it
    can be read against it (this machine's speed drifts about 2x).
    """
    space = pymunk.Space()
    body = pymunk.Body(1.0, pymunk.moment_for_box(1.0, (1.0, 1.0)))
    body.velocity = (1.0, 0.0)
    space.add(body, pymunk.Poly.create_box(body, (1.0, 1.0)))
    t0 = time.process_time()
    for _ in range(REFERENCE_STEPS):
        space.step(0.005)
    return REFERENCE_STEPS / (time.process_time() - t0)


def _spin(n: int) -> int:
    """A fixed pure-Python workload (the kind of work an env step is)."""
    s = 0
    for i in range(n):
        s += i * i % 7
    return s


SPIN_STEPS = 2_000_000


def two_process_scaling(rounds: int = 3) -> float:
    """The machine's own scaling now: 2 x one process's wall time over two at once.

    A fixed pure-Python workload, run alone and then in two forked processes
    side by side, in turn, ``rounds`` times; the median pair's ratio. 2.0 on
    two idle cores; two cores a hypervisor shares give less, and no vector
    env can scale better than this.
    """
    ctx = multiprocessing.get_context("fork")
    ratios = []
    for _ in range(rounds):
        t0 = time.perf_counter()
        _spin(SPIN_STEPS)
        one = time.perf_counter() - t0
        workers = [ctx.Process(target=_spin, args=(SPIN_STEPS,)) for _ in range(2)]
        t0 = time.perf_counter()
        for w in workers:
            w.start()
        for w in workers:
            w.join()
        ratios.append(2.0 * one / (time.perf_counter() - t0))
    return float(statistics.median(ratios))
