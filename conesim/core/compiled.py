"""numba's ``njit`` with an on-disk cache that is never stale, shared by the kernel modules.

The kernel modules (``planner.kernels``, ``planner.fused``,
``localization.ekf.kernels``) decorate their kernels with
``cached_njit(_probe, "<module>")``. Compiled machine code is cached on disk
(beside the module's file, else under ``NUMBA_CACHE_DIR`` or the user's
cache directory) and filed under a digest of the kernel's code and of all
the code and constants it reaches, in any file
(:mod:`conesim.core.kernel_cache`, :mod:`conesim.core.kernel_digest`): after
an edit, a process loads only code compiled from the code it imported; no
cache needs clearing. With no writable cache directory (numba would raise
when decorating), the probe, a do-nothing function of the kernel module
(the directory depends on its file), finds out first: the module's kernels
then compile in every process, with one warning per module, instead of
failing to import.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Any

from numba import njit
from numba.extending import is_jitted

from conesim.core import kernel_cache

_packages: set[str] = set()
"""The kernel modules' top-level packages, followed by the digest."""


def cached_njit(probe: Callable[[], None], owner: str) -> Callable[[Any], Any]:
    """The decorator for the kernels of module ``owner``: ``njit`` with the cache above.

    Args:
        probe: a do-nothing function defined in the kernel module.
        owner: the module's name (its top-level package is followed by the digest).

    Returns:
        The decorator, or ``njit(cache=False)`` with a warning when numba
        can cache nothing from the module's directory.
    """
    _packages.add(owner.split(".", maxsplit=1)[0])
    try:
        njit(cache=True)(probe)
    except RuntimeError:
        warnings.warn(
            f"{owner}: numba has no writable cache directory (set NUMBA_CACHE_DIR); "
            "the kernels are compiled in every process",
            RuntimeWarning,
            stacklevel=2,
        )
        return njit(cache=False)
    return _cached


def _cached(func: Callable[..., Any]) -> Any:
    dispatcher = njit(cache=False)(func)
    if not is_jitted(dispatcher):  # NUMBA_DISABLE_JIT
        return dispatcher
    cache = kernel_cache.DependencyCache(func, _packages, _on_miss)
    return kernel_cache.install(dispatcher, cache)


def _on_miss(retry: Callable[[], Any]) -> None:
    """A cache miss: numba compiles."""
