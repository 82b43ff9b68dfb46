"""numba's ``njit`` with an on-disk cache where one can be written, shared by the kernel modules.

The modules of ``planner.kernels``, ``planner.fused`` and
``localization.ekf.kernels`` compile with ``cache=True``: later processes load
the machine code instead of compiling it again (seconds). numba looks for a
cache directory beside the kernel's source file, then under
``NUMBA_CACHE_DIR`` or the user's cache directory; with none writable,
``njit(cache=True)`` raises when it decorates. :func:`cached_njit` asks first,
with a do-nothing function from the kernel module itself (the directory
depends on its file), and falls back to compiling in every process, with one
warning per module, instead of failing to import.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Any

from numba import njit


def cached_njit(probe: Callable[[], None], owner: str) -> Any:
    """``njit(cache=True)`` if numba can cache ``probe``'s module, else ``njit()`` and a warning.

    Args:
        probe: a do-nothing function defined in the kernel module.
        owner: the module's name, for the warning.

    Returns:
        The decorator for the module's kernels.
    """
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
    return njit(cache=True)
