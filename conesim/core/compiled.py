"""numba's ``njit`` for conesim's kernels: a cache that is never stale, a notice while compiling,
and cold compiles shared among helper processes.

The kernel modules (``planner.kernels``, ``planner.fused``,
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
  (the planner's) that meets a cold cache starts one helper process per core
  (up to :data:`MAX_HELPERS`) and waits for them. Each helper imports the
  kernels as plain Python functions that record their argument types, runs
  the warm-up interpreted (milliseconds), then compiles each kernel the
  warm-up called from Python, for the types seen, largest first, claiming
  each so that no two helpers compile one kernel (:mod:`conesim.core.kernel_workers`).
  The warm-up then loads them from the cache; whatever the helpers did not
  provide it compiles itself, so the result is the same either way.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import importlib
import json
import os
import sys
import traceback
import types
import warnings
from collections.abc import Callable, Sequence
from typing import Any, TypeVar, cast

from numba import njit, typeof
from numba.extending import is_jitted

from conesim.core import kernel_cache, kernel_digest, kernel_workers

MAX_HELPERS = 4
"""Helper processes for a cold warm-up at most (past a few, the largest kernel sets the time)."""

HELPER_TIMEOUT_S = 1800.0
"""Seconds the helpers get in all; any still running then are killed and the warm-up compiles."""

COLD_SECONDS = {1: 30, 2: 16}
"""About how long compiling all the kernels takes, by processes compiling (said in the notice)."""

_F = TypeVar("_F", bound=Callable[[], object])

_HELPER_CODE = (
    "import json, sys; sys.path[:] = json.loads(sys.argv[1]); "
    "from conesim.core.compiled import run_helper; sys.exit(run_helper(sys.argv[2:]))"
)


@dataclasses.dataclass
class _WarmUp:
    """A running :func:`parallel_warm_up`: the name a helper imports, and whether helpers ran."""

    target: str
    helped: bool = False


@dataclasses.dataclass
class _Recording:
    """A helper's record of the kernel calls its warm-up made from Python, in order."""

    calls: dict[tuple[_Recorder, tuple[Any, ...]], None] = dataclasses.field(default_factory=dict)
    depth: int = 0


@dataclasses.dataclass
class _State:
    packages: set[str] = dataclasses.field(default_factory=set)
    announced: bool = False
    warm_up: _WarmUp | None = None
    recording: _Recording | None = None  # in a helper, while its warm-up runs
    in_helper: bool = False


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
    if _state.recording is not None:
        return _Recorder
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
    """Let ``func``, a module-level warm-up of no arguments, share a cold compile among helpers.

    Why: compiling the planner's kernels from a cold cache takes tens of
    seconds in one process; the helpers use the other cores. A warm cache
    costs nothing extra: helpers start only on a cache miss inside ``func``.
    """
    target = f"{func.__module__}:{func.__qualname__}"

    @functools.wraps(func)
    def warm_up() -> object:
        if _state.recording is not None or _state.in_helper:
            return func()
        outer, _state.warm_up = _state.warm_up, _WarmUp(target)
        try:
            return func()
        finally:
            _state.warm_up = outer

    return cast(_F, warm_up)


def notice(*, cached: bool = True) -> str:
    """The line written to stderr when a process first compiles a kernel."""
    if not cached:
        return (
            "conesim: compiling the numba kernels (no writable cache directory, so in every "
            f"run: set NUMBA_CACHE_DIR; about {COLD_SECONDS[1]} s) ..."
        )
    cores = _cores()
    on = f"{cores} cores" if cores > 1 else "1 core"
    return (
        "conesim: compiling the numba kernels (first run after an install or an edit; "
        f"up to about {COLD_SECONDS[min(cores, 2)]} s on {on}) ..."
    )


def run_helper(argv: Sequence[str]) -> int:
    """A helper process's work (see the module docstring); ``argv``: warm-up target, claims dir.

    Returns:
        0, or 1 if the interpreted warm-up or compiling some kernel failed (the
        warm-up compiles what is missing then, and reports any error itself).
    """
    target, claims = argv
    recording = _state.recording = _Recording()
    module, _, name = target.partition(":")
    failed = 0
    try:
        getattr(importlib.import_module(module), name)()
    except Exception:  # compile what was recorded before it
        traceback.print_exc()
        failed = 1
    finally:
        _state.recording = None
        _state.in_helper = True
    _replace_recorders()
    calls = sorted(
        recording.calls, key=lambda call: -kernel_digest.code_size(call[0].func, _state.packages)
    )
    for recorder, sig in calls:
        func = recorder.func
        if kernel_workers.claim(claims, f"{func.__module__}.{func.__qualname__}{sig}"):
            try:
                recorder.dispatcher.compile(sig)
            except Exception:
                traceback.print_exc()
                failed = 1
    return failed


def _cached(func: Callable[..., Any]) -> Any:
    dispatcher = njit(cache=False)(func)
    if not is_jitted(dispatcher):  # NUMBA_DISABLE_JIT
        return dispatcher
    cache = kernel_cache.DependencyCache(func, _state.packages, _on_miss)
    return kernel_cache.install(dispatcher, cache)


def _uncached(func: Callable[..., Any]) -> Any:
    dispatcher = njit(cache=False)(func)
    if not is_jitted(dispatcher):
        return dispatcher
    return kernel_cache.install(dispatcher, kernel_cache.AnnouncingNullCache(_on_uncached))


def _on_uncached(retry: Callable[[], Any]) -> None:
    _announce(cached=False)


def _on_miss(retry: Callable[[], Any]) -> Any:
    """A cached kernel missed: say so once, and in a parallel warm-up, start the helpers once."""
    if _state.recording is not None or _state.in_helper:
        return None
    _announce(cached=True)
    warm_up = _state.warm_up
    if warm_up is None or warm_up.helped:
        return None
    warm_up.helped = True
    count = min(_cores(), MAX_HELPERS)
    if count < 2 or not sys.executable:
        return None
    command = [sys.executable, "-c", _HELPER_CODE, json.dumps(sys.path), warm_up.target]
    kernel_workers.run(command, count, HELPER_TIMEOUT_S)
    return retry()


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


class _Recorder:
    """A kernel in a helper's warm-up: runs as Python, recording the types it is called with
    from Python (not from other kernels); becomes its dispatcher after the warm-up."""

    def __init__(self, func: Callable[..., Any]) -> None:
        self.func = func
        functools.update_wrapper(self, func)

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        recording = _state.recording
        if recording is None:
            return self.func(*args, **kwargs)
        if recording.depth == 0 and not kwargs:
            # ValueError: a type numba does not know (the warm-up will say so)
            with contextlib.suppress(ValueError):
                recording.calls.setdefault((self, tuple(typeof(a) for a in args)), None)
        recording.depth += 1
        try:
            return self.func(*args, **kwargs)
        finally:
            recording.depth -= 1

    @functools.cached_property
    def dispatcher(self) -> Any:
        """The kernel as ``cached_njit`` makes it in any other process."""
        return _cached(self.func)


def _replace_recorders() -> None:
    """Put each recorder's dispatcher where the recorder was, in every module of the packages,
    so that compiled kernels call compiled kernels."""
    for module in list(sys.modules.values()):
        if isinstance(module, types.ModuleType) and (
            module.__name__.split(".", maxsplit=1)[0] in _state.packages
        ):
            for name, value in list(vars(module).items()):
                if isinstance(value, _Recorder):
                    setattr(module, name, value.dispatcher)
