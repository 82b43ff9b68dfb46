"""numba's ``njit`` for conesim's kernels: a cache that is never stale, a notice while compiling,
and cold compiles shared among helper processes.

The kernel modules (``planner.kernels``, ``planner.kernel_chains``,
``localization.ekf.kernels``) decorate their kernels with
``cached_njit(_probe, "<module>")``. What that gives:

- **A cache that follows edits.** Compiled machine code is cached on disk
  (beside the module's file, else under ``NUMBA_CACHE_DIR`` or the user's
  cache directory) and filed under a digest of the kernel's code and of all
  the code and constants it reaches, in any file
  (:mod:`conesim.core.kernel_cache`, :mod:`conesim.core.kernel_digest`):
  after an edit a process loads only code compiled from the code it
  imported; no cache needs clearing. With no writable cache directory
  (numba would raise when decorating), the probe, a do-nothing function of
  the kernel module, finds out first: the module's kernels then compile in
  every process, with one warning per module.
- **A notice.** The first time a process finds a kernel missing from the
  cache (or has no cache), it writes one line to stderr (:func:`notice`), so
  that a first run is not silent while it compiles; loading prints nothing.
- **Parallel cold compiles.** A warm-up decorated with :func:`parallel_warm_up`
  (the planner's) whose first call of a kernel misses the cache stops there,
  and has every kernel call it makes compiled into the cache by this process
  and one helper process per further idle core (up to :data:`MAX_HELPERS`;
  :mod:`conesim.core.kernel_workers`), then runs again, loading them. What
  the helpers did not provide it compiles itself, so the result is the same.
  With no idle core for a helper it goes on compiling by itself.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import os
import sys
import time
import warnings
import weakref
from collections.abc import Callable
from typing import Any, TypeVar, cast

from numba import njit
from numba.extending import is_jitted

from conesim.core import kernel_cache, kernel_workers

MAX_HELPERS = 3
"""Helper processes for a cold warm-up at most (past a few, the largest kernel sets the time)."""

HELPER_TIMEOUT_S = 1800.0
"""Seconds the helpers get; any still running then are killed (the warm-up compiles the rest)."""

COLD_SECONDS = {1: 27, 2: 16}
"""About how long a cold ``conesim run`` sets up, by idle cores (said in the notice)."""

_F = TypeVar("_F", bound=Callable[..., object])


class _ColdCache(BaseException):
    """Raised out of a parallel warm-up's first cache miss (a BaseException: no ``except
    Exception`` on the way swallows it), to compile everything before running it again."""


@dataclasses.dataclass
class _WarmUp:
    """A running :func:`parallel_warm_up`: ``stopped`` at its first miss, with ``helpers``
    (0: it goes on compiling by itself)."""

    stopped: bool = False
    helpers: int = 0


@dataclasses.dataclass
class _State:
    packages: set[str] = dataclasses.field(default_factory=set)
    kernels: weakref.WeakSet[Any] = dataclasses.field(default_factory=weakref.WeakSet)
    announced: bool = False
    warm_up: _WarmUp | None = None


_state = _State()


def cached_njit(probe: Callable[[], None], owner: str) -> Callable[[Any], Any]:
    """The decorator for the kernels of module ``owner``: ``njit`` with the cache above.

    Args:
        probe: a do-nothing function defined in the kernel module.
        owner: the module's name (its top-level package is followed by the digest).

    Returns:
        The decorator, or ``njit(cache=False)`` with a warning when numba
        can cache nothing from the module's directory.
    """
    _state.packages.add(owner.split(".", maxsplit=1)[0])
    try:
        njit(cache=True)(probe)
    except RuntimeError:
        warnings.warn(
            f"{owner}: numba has no writable cache directory (set NUMBA_CACHE_DIR); "
            "the kernels are compiled in every process",
            RuntimeWarning,
            stacklevel=2,
        )
        return _uncached
    return _cached


def parallel_warm_up(func: _F) -> _F:
    """Let ``func``, a warm-up that calls kernels, compile a cold cache's kernels in parallel.

    Why: compiling the planner's kernels from a cold cache takes tens of
    seconds in one process; helpers use the other cores. ``func`` must be
    safe to run more than once: on a cold cache it is stopped at its first
    miss, runs as Python, and runs again. A warm cache costs nothing extra,
    and neither do busy cores: where fewer than two are idle (other work
    holds them) it just runs, as helpers would only add their start-up.
    """

    @functools.wraps(func)
    def warm_up(*args: Any, **kwargs: Any) -> object:
        if _state.warm_up is not None or kernel_workers.discovering() or _cores() < 2:
            return func(*args, **kwargs)
        warm_up = _state.warm_up = _WarmUp()
        try:
            return func(*args, **kwargs)
        except _ColdCache:
            pass
        finally:
            _state.warm_up = None
        run = functools.partial(func, *args, **kwargs)
        kernel_workers.compile_in_parallel(
            run, _state.kernels, _state.packages, warm_up.helpers, HELPER_TIMEOUT_S
        )
        return func(*args, **kwargs)

    return cast(_F, warm_up)


def notice(*, cached: bool = True) -> str:
    """The line written to stderr when a process first compiles a kernel."""
    if not cached:
        return (
            "conesim: compiling the numba kernels (no writable cache directory, so in every "
            f"run: set NUMBA_CACHE_DIR; about {COLD_SECONDS[1]} s on an idle core) ..."
        )
    cores = _cores()
    on = f"{cores} idle cores" if cores > 1 else "1 idle core"
    return (
        "conesim: compiling the numba kernels (first run after an install or an edit; "
        f"about {COLD_SECONDS[min(cores, max(COLD_SECONDS))]} s on {on}) ..."
    )


def _cached(func: Callable[..., Any]) -> Any:
    dispatcher = njit(cache=False)(func)
    if not is_jitted(dispatcher):  # NUMBA_DISABLE_JIT
        return dispatcher
    cache = kernel_cache.DependencyCache(func, _state.packages, _on_miss)
    _state.kernels.add(dispatcher)
    return kernel_cache.install(dispatcher, cache)


def _uncached(func: Callable[..., Any]) -> Any:
    dispatcher = njit(cache=False)(func)
    if not is_jitted(dispatcher):
        return dispatcher
    return kernel_cache.install(dispatcher, kernel_cache.AnnouncingNullCache(_on_uncached))


def _on_uncached() -> None:
    _announce(cached=False)


def _on_miss() -> None:
    """A cached kernel missed: say so (once); in a parallel warm-up, stop it (once)."""
    if kernel_workers.discovering():
        return
    _announce(cached=True)
    warm_up = _state.warm_up
    if warm_up is not None and not warm_up.stopped:
        warm_up.stopped = True
        # One helper per idle core beyond this process's; 1.6 idle cores give one.
        warm_up.helpers = min(_cores() - 1, MAX_HELPERS, int(_idle_cores() - 0.6))
        if warm_up.helpers > 0:
            raise _ColdCache


def _announce(*, cached: bool) -> None:
    if _state.announced:
        return
    _state.announced = True
    with contextlib.suppress(OSError, ValueError, AttributeError):  # no usable stderr
        print(notice(cached=cached), file=sys.stderr, flush=True)


def _cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        return os.cpu_count() or 1


def _idle_cores() -> float:
    """Cores idle over a fifth of a second (Linux: /proc/stat); elsewhere all of them."""
    try:
        before = _cpu_times()
        time.sleep(0.2)
        after = _cpu_times()
    except (OSError, ValueError, IndexError):
        return float(_cores())
    total = sum(after) - sum(before)
    idle = (after[3] + after[4]) - (before[3] + before[4])  # idle, iowait
    cpus = os.cpu_count() or 1
    return cpus * idle / total if total > 0 else float(_cores())


def _cpu_times() -> list[int]:
    """The first line of /proc/stat: user, nice, system, idle, iowait, ... (clock ticks)."""
    with open("/proc/stat", encoding="ascii") as stat:
        fields = stat.readline().split()
    if fields[0] != "cpu":
        raise ValueError(fields[0])
    return [int(v) for v in fields[1:]]
