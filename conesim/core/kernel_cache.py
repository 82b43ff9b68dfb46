"""numba's on-disk cache for one kernel, filed under the digest of everything it compiles from.

numba stamps a function's cache index with its own source file's modification
time and size, and serves the cached machine code while that stamp matches:
an edited callee in another file, or a constant imported from one, leaves the
caller's stale code in use (``make clean-cache`` used to be the remedy).
:class:`DependencyCache` stamps the index with
:func:`conesim.core.kernel_digest.digest` instead: any change to the code the
kernel can reach gives another stamp, numba then finds the index stale,
compiles, and overwrites the old entries (they do not pile up). The digest is
taken at the kernel's first load, when every global it names is bound.

Reading and writing an index take a lock on the cache directory (shared,
exclusive): numba writes a new index before the data file it names, and two
processes saving entries of one index at once (two runs started together, or
the helpers of :func:`conesim.core.compiled.parallel_warm_up`) can lose or
swap entries.

numba internals relied on (numba is pinned to 0.68.x in pyproject.toml;
``tests/core/test_kernel_cache.py`` checks each of them, and fails loudly if
a numba upgrade moves them):

- ``numba.core.caching.FunctionCache(py_func)``, the cache ``njit(cache=True)``
  installs, with ``load_overload(sig, target_context)`` returning None on a
  miss, ``save_overload(sig, data)``, and the attributes ``_py_func``,
  ``_cache_path`` and ``_cache_file._source_stamp`` (compared with the stamp
  pickled in the index: equal is fresh);
- ``numba.core.caching.NullCache``, the cache of ``njit(cache=False)``;
- a dispatcher's ``_cache`` attribute, through which ``Dispatcher.compile``
  loads and saves (:func:`install`).
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Callable, Iterator, Set
from typing import Any

from numba.core.caching import FunctionCache, NullCache

from conesim.core import kernel_digest

try:
    import fcntl
except ImportError:  # not POSIX: no lock (numba's own behaviour)
    fcntl = None  # type: ignore[assignment]

LOCK_NAME = "conesim-kernels.lock"
"""The lock file in each cache directory."""

OnMiss = Callable[[], None]
"""Called on a cache miss, before numba compiles (it may raise to stop the compile)."""


class DependencyCache(FunctionCache):
    """``FunctionCache`` stamped with the digest of the kernel's reachable code, and locked.

    Args:
        py_func: the kernel's Python function.
        packages: the top-level packages the digest follows (read at the first load).
        on_miss: called when the cache has no entry for a signature.
    """

    def __init__(self, py_func: Callable[..., Any], packages: Set[str], on_miss: OnMiss) -> None:
        super().__init__(py_func)
        self._packages = packages
        self._on_miss = on_miss
        self._stamped = False

    def load_overload(self, sig: Any, target_context: Any) -> Any:
        """The cached compile result for ``sig``, or None: numba compiles it then."""
        self._stamp()
        with self._locked(exclusive=False):
            data = super().load_overload(sig, target_context)
        if data is None:
            self._on_miss()
        return data

    def save_overload(self, sig: Any, data: Any) -> None:
        """Save the compile result for ``sig`` under the digest."""
        self._stamp()
        with self._locked(exclusive=True):
            super().save_overload(sig, data)

    def _stamp(self) -> None:
        if not self._stamped:
            stamp = kernel_digest.digest(self._py_func, self._packages)
            self._cache_file._source_stamp = f"conesim-digest:{stamp}"
            self._stamped = True

    @contextlib.contextmanager
    def _locked(self, *, exclusive: bool) -> Iterator[None]:
        """Hold the cache directory's lock; without the directory (or fcntl), no lock."""
        if fcntl is None:
            yield
            return
        try:
            if exclusive:
                os.makedirs(self._cache_path, exist_ok=True)
            fd = os.open(os.path.join(self._cache_path, LOCK_NAME), os.O_RDWR | os.O_CREAT, 0o666)
        except OSError:  # no directory yet (nothing to load), or none writable
            yield
            return
        try:
            fcntl.flock(fd, fcntl.LOCK_EX if exclusive else fcntl.LOCK_SH)
            yield
        finally:
            os.close(fd)  # releases the lock


class AnnouncingNullCache(NullCache):
    """``NullCache`` (no cache directory): every load misses, and says so to ``on_miss``."""

    def __init__(self, on_miss: OnMiss) -> None:
        self._on_miss = on_miss

    def load_overload(self, sig: Any, target_context: Any) -> Any:
        """None, after telling ``on_miss``."""
        self._on_miss()


def install(dispatcher: Any, cache: FunctionCache | NullCache) -> Any:
    """Give ``dispatcher`` (from ``njit(cache=False)``) ``cache``; returns the dispatcher."""
    dispatcher._cache = cache
    return dispatcher
