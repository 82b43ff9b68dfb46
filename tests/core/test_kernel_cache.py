"""numba's cache of conesim's kernels follows edits of any file a kernel reaches, in fresh
processes on a temporary kernel package; and the numba internals it relies on are where
``conesim.core.kernel_cache`` says."""

from __future__ import annotations

import inspect
from pathlib import Path

import numba
from numba.core import caching, dispatcher

from tests.core.demo_kernels import cache_files, edit, run, write_package


def test_an_edit_anywhere_a_kernel_reaches_is_compiled_and_an_unchanged_tree_is_loaded(
    tmp_path: Path,
) -> None:
    """Compile and cache; edit the callee's callee (another file), then a constant of a
    plain module: each time a fresh process computes the new value, and with nothing
    edited it loads ``chain`` from the cache. Old entries are replaced, not kept."""
    package = write_package(tmp_path)
    first, _ = run(tmp_path)
    assert first["value"] == (3.0 + 1.0) * 3.0 * 2.0
    assert first["misses"]["chain"] == 1
    again, _ = run(tmp_path)
    assert again["value"] == first["value"]
    assert again["hits"]["chain"] == 1
    assert again["misses"] == {"chain": 0, "offset": 0}

    edit(package / "common.py", "x + 1.0", "x + 5.0")
    edited, _ = run(tmp_path)
    assert edited["value"] == (3.0 + 5.0) * 3.0 * 2.0
    assert edited["misses"]["chain"] == 1
    assert run(tmp_path)[0]["hits"]["chain"] == 1

    edit(package / "consts.py", "SCALE = 2.0", "SCALE = 0.5")
    scaled, _ = run(tmp_path)
    assert scaled["value"] == (3.0 + 5.0) * 3.0 * 0.5
    assert scaled["misses"]["chain"] == 1
    assert len(cache_files(package, "chain.chain-*.nbc")) == 1


def test_a_comment_or_docstring_elsewhere_in_the_callees_file_changes_nothing(
    tmp_path: Path,
) -> None:
    """The digest is of the code, not of the file: editing outside any function keeps the cache."""
    package = write_package(tmp_path)
    run(tmp_path)
    edit(package / "common.py", '"""Nothing."""', '"""Nothing at all."""\n# a comment')
    assert run(tmp_path)[0]["hits"]["chain"] == 1


def test_plain_numba_serves_stale_code_after_a_callee_edit(tmp_path: Path) -> None:
    """Why ``cached_njit`` exists: with ``njit(cache=True)`` the same edit leaves the old
    value in use. If this fails, numba has changed how it checks its cache: re-examine
    ``conesim.core.kernel_cache``."""
    package = write_package(tmp_path)
    for name in ("common.py", "step.py", "chain.py"):
        plain = "from numba import njit\n_compiled = njit(cache=True)"
        edit(package / name, "_compiled = cached_njit(_probe, __name__)", plain)
    assert run(tmp_path)[0]["value"] == 24.0
    edit(package / "common.py", "x + 1.0", "x + 5.0")
    stale, _ = run(tmp_path)
    assert stale["value"] == 24.0
    assert stale["hits"]["chain"] == 1


def test_the_numba_internals_relied_on_are_there() -> None:
    """``conesim.core.kernel_cache``'s list: a numba upgrade that moves any of these must
    fail here, not serve stale code."""
    assert numba.__version__.startswith("0.68."), numba.__version__

    def probe(x: float) -> float:
        return x

    cache = caching.FunctionCache(probe)
    assert cache._py_func is probe
    assert isinstance(cache._cache_path, str)
    assert hasattr(cache._cache_file, "_source_stamp")
    assert list(inspect.signature(cache.load_overload).parameters) == ["sig", "target_context"]
    assert list(inspect.signature(cache.save_overload).parameters) == ["sig", "data"]
    # The index is fresh when its pickled stamp equals _source_stamp, else it is empty.
    index_source = inspect.getsource(caching.IndexDataCacheFile._load_index)
    assert "stamp != self._source_stamp" in index_source
    # Dispatcher.compile loads and saves through the _cache attribute that njit sets.
    source = inspect.getsource(dispatcher.Dispatcher.compile)
    assert "self._cache.load_overload(sig, self.targetctx)" in source
    assert "self._cache.save_overload(sig, cres)" in source
    assert isinstance(numba.njit(cache=False)(probe)._cache, caching.NullCache)
    assert type(numba.njit(cache=True)(probe)._cache) is caching.FunctionCache
