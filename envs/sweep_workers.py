"""Where a sweep's runs run: in this process, a local process pool, or Ray.

Each runs ``run_point`` (one scenario, with the autopilot, to an
``Outcome``: ``result.json``'s data and ``run.png``'s bytes, or the error
it raised with its traceback) and yields each outcome as it comes, in the
order the runs finish. A run's result depends on its scenario alone, not on
the process it ran in, the runs before it there or the order, so every
executor gives the same results.

* ``serial``: one after the other in this process (``--workers 1``).
* ``pool``: ``workers`` processes forked from a fork server that imported
  conesim once (``forkserver``; ``spawn`` where there is none: nothing of
  this process's state inherited either way), warmed up when they start
  (``warm_worker``: numba's kernels loaded from the cache) and reused for
  every run. At most one run per
  worker is in flight, so when a worker dies (killed, out of memory) the
  runs it may have held are known: they are run again in a new pool, and a
  run in flight at ``MAX_ATTEMPTS`` deaths is recorded as an error
  (``WorkerDied``). Workers ignore SIGINT; the sweep's process ends them.
* ``ray``: Ray actors (``pip install "conesim[ray]"``), one per CPU of a
  local Ray it starts with ``workers`` CPUs, or of the cluster at
  ``address`` (whose nodes must have conesim installed). Each actor is
  warmed once when it starts, as a pool worker is (the kernels loaded), and
  reused for every run it is given, one at a time, so when an actor dies
  the run it held is known: it is run again on a new actor, and a run in
  flight at ``MAX_ATTEMPTS`` deaths is recorded as an error
  (``WorkerDied``), as in the pool. (Ray tasks instead landed on workers
  that had not loaded the kernels, and Ray's own retry hid which run a
  death cost.) The actors are ended when the sweep ends or is interrupted.
"""

from __future__ import annotations

import contextlib
import logging
import multiprocessing
import os
import signal
import tempfile
import traceback
from collections import deque
from collections.abc import Generator, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path
from typing import Any, Literal, get_args

from gymnasium.error import DependencyNotInstalled

from conesim.envs.scenario import Scenario
from conesim.envs.sweep_file import SweepPoint
from conesim.envs.sweep_store import Outcome, RunError

Pictures = Literal["all", "failed", "none"]
"""Which runs get a ``run.png``: every run, those not clean, or none."""
PICTURES: tuple[str, ...] = get_args(Pictures)
MAX_ATTEMPTS = 2
"""A run in flight when this many workers died is recorded as an error."""

Results = Generator[tuple[SweepPoint, Outcome], None, None]


def run_point(scenario: Scenario, pictures: Pictures = "all") -> Outcome:
    """Run one scenario; its result and picture, or the error it raised.

    ``pictures``: draw ``run.png`` for every run, only for a run that is not
    clean, or for none (drawing takes longer than a short run).
    """
    from conesim.envs.run_plot import save_run_picture  # noqa: PLC0415 (in the worker)
    from conesim.envs.runner import run_scenario  # noqa: PLC0415
    from conesim.tracks import load_track  # noqa: PLC0415
    from conesim.tracks.global_path import global_path_for_track  # noqa: PLC0415

    try:
        result = run_scenario(scenario)
        if pictures == "none" or (pictures == "failed" and result.clean):
            return Outcome(payload=result.to_json())
        track = load_track(scenario.track)
        with tempfile.TemporaryDirectory(prefix="conesim-sweep-") as tmp:
            picture = Path(tmp) / "run.png"
            save_run_picture(result, track, global_path_for_track(track), picture)
            data = picture.read_bytes()
        return Outcome(payload=result.to_json(), picture=data)
    except Exception as exc:
        return Outcome(error=RunError(type(exc).__name__, str(exc), traceback.format_exc()))


def warm_worker() -> None:
    """A pool worker's start: ignore Ctrl-C (the sweep ends it), load the kernels."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    from conesim.planner.autopilot import warm_up_planner  # noqa: PLC0415

    warm_up_planner()


def serial(points: Sequence[SweepPoint], pictures: Pictures = "all") -> Results:
    """The runs one after the other, in this process."""
    for point in points:
        yield point, run_point(point.scenario, pictures)


PRELOAD = ["conesim.envs.sweep_workers", "conesim.envs.runner", "conesim.envs.run_plot"]
"""What the fork server imports once, for every worker it forks."""


def _context() -> multiprocessing.context.BaseContext:
    """``forkserver`` where there is one (POSIX): conesim imported once, in the server,
    the workers forked from it; else ``spawn``. Neither inherits this process's state."""
    if "forkserver" not in multiprocessing.get_all_start_methods():
        return multiprocessing.get_context("spawn")
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload(PRELOAD)
    return context


def _died(deaths: int) -> Outcome:
    message = f"the worker process running it died ({deaths} times); see the sweep's log"
    return Outcome(error=RunError("WorkerDied", message, message + "\n"))


def pool(points: Sequence[SweepPoint], workers: int, pictures: Pictures = "all") -> Results:
    """The runs on ``workers`` local processes (see the module docstring)."""
    context = _context()
    queue = deque(points)
    deaths: dict[str, int] = {}
    while queue:
        before = set(multiprocessing.active_children())
        executor = ProcessPoolExecutor(workers, mp_context=context, initializer=warm_worker)
        running: dict[Future[Outcome], SweepPoint] = {}
        broken = False
        try:
            while queue or running:
                while queue and len(running) < workers and not broken:
                    point = queue.popleft()
                    running[executor.submit(run_point, point.scenario, pictures)] = point
                if not running:
                    break
                done, _ = wait(running, return_when=FIRST_COMPLETED)
                for future in done:
                    point = running.pop(future)
                    try:
                        outcome = future.result()
                    except BrokenProcessPool:
                        broken = True
                        deaths[point.run_id] = deaths.get(point.run_id, 0) + 1
                        if deaths[point.run_id] < MAX_ATTEMPTS:
                            queue.appendleft(point)
                            continue
                        outcome = _died(deaths[point.run_id])
                    yield point, outcome
                if broken and not running:
                    logging.getLogger(__name__).error("a worker process died; starting new ones")
                    break
        except BaseException:
            _end(executor, before)
            raise
        executor.shutdown(wait=not broken, cancel_futures=True)


def _end(executor: ProcessPoolExecutor, before: set[Any]) -> None:
    """Stop the pool now: cancel what has not started, end this pool's workers."""
    executor.shutdown(wait=False, cancel_futures=True)
    for process in set(multiprocessing.active_children()) - before:
        process.kill()
        process.join(5.0)


class RayStartError(Exception):
    """Ray could not be started, or the cluster reached (one line: why)."""


def _import_ray() -> Any:
    try:
        import ray  # noqa: PLC0415
    except ImportError:
        raise DependencyNotInstalled(
            'Ray is not installed: install the ray extra, pip install "conesim[ray]"'
        ) from None
    return ray


@contextlib.contextmanager
def ray_session(workers: int, address: str | None) -> Iterator[Any]:
    """Ray, started (a local Ray of ``workers`` CPUs) or connected to (``address``)
    unless it already is, and shut down again on exit if it was started here.

    Raises:
        RayStartError: Ray would not start, or the cluster cannot be reached.
        gymnasium.error.DependencyNotInstalled: Ray is not installed.
    """
    ray = _import_ray()
    started = not ray.is_initialized()
    if started:
        options: dict[str, Any] = {
            "include_dashboard": False,
            "logging_level": logging.WARNING,
            "log_to_driver": False,
        }
        try:
            if address is None:
                ray.init(num_cpus=workers, **options)
            else:
                ray.init(address=address, **options)
        except Exception as exc:  # Ray raises ConnectionError, RuntimeError, ValueError, ...
            where = "a local Ray" if address is None else f"the Ray cluster at {address}"
            reason = (str(exc).strip().splitlines() or [type(exc).__name__])[0]
            raise RayStartError(f"cannot start or reach {where}: {reason}") from None
    try:
        yield ray
    finally:
        if started:
            ray.shutdown()


def ray_tasks(
    points: Sequence[SweepPoint], workers: int, address: str | None, pictures: Pictures = "all"
) -> Results:
    """The runs on Ray actors, one per CPU (see the module docstring)."""
    with ray_session(workers, address) as ray:
        yield from _ray_loop(ray, points, workers, address, pictures)


class RunActor:
    """A Ray actor that runs sweep runs: warmed once when it starts (the planner's
    kernels loaded, as a pool worker is), then given one run at a time."""

    def __init__(self) -> None:
        from conesim.planner.autopilot import warm_up_planner  # noqa: PLC0415 (in the actor)

        warm_up_planner()

    def run(self, scenario: Scenario, pictures: Pictures) -> Outcome:
        """One run (``run_point``)."""
        return run_point(scenario, pictures)


def _ray_loop(
    ray: Any, points: Sequence[SweepPoint], workers: int, address: str | None, pictures: Pictures
) -> Results:
    actor_class = ray.remote(num_cpus=1, max_restarts=0, max_task_retries=0)(RunActor)
    slots = workers if address is None else max(1, int(ray.cluster_resources().get("CPU", 1)))
    slots = min(slots, len(points))
    queue = deque(points)
    deaths: dict[str, int] = {}
    idle: list[Any] = [actor_class.remote() for _ in range(slots)]
    running: dict[Any, tuple[SweepPoint, Any]] = {}
    try:
        while queue or running:
            while queue and idle:
                point, actor = queue.popleft(), idle.pop()
                running[actor.run.remote(point.scenario, pictures)] = (point, actor)
            done, _ = ray.wait(list(running), num_returns=1)
            for ref in done:
                point, actor = running.pop(ref)
                try:
                    outcome = ray.get(ref)
                except ray.exceptions.RayActorError as exc:  # the actor's process died
                    ray.kill(actor, no_restart=True)
                    idle.append(actor_class.remote())
                    deaths[point.run_id] = deaths.get(point.run_id, 0) + 1
                    if deaths[point.run_id] < MAX_ATTEMPTS:
                        logging.getLogger(__name__).error("a Ray actor died; starting a new one")
                        queue.appendleft(point)
                        continue
                    outcome = _ray_error(exc, deaths[point.run_id])
                except ray.exceptions.RayError as exc:  # the run's arguments or result, say
                    idle.append(actor)
                    outcome = _ray_error(exc, None)
                else:
                    idle.append(actor)
                yield point, outcome
    finally:
        for actor in idle + [actor for _, actor in running.values()]:
            ray.kill(actor, no_restart=True)


def _ray_error(exc: Exception, deaths: int | None) -> Outcome:
    text = f"{type(exc).__name__}: {exc}"
    first = text.splitlines()[0]
    if deaths is None:
        return Outcome(error=RunError(type(exc).__name__, first, text))
    message = f"the Ray actor running it died ({deaths} times): {first}"
    return Outcome(error=RunError("WorkerDied", message, text))


def default_workers() -> int:
    """All the cores this process may use."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1
