"""``cached_njit``'s notice while compiling, and ``parallel_warm_up``'s helpers, in fresh
processes on a temporary kernel package (and once on the planner's own warm-up)."""

from __future__ import annotations

from pathlib import Path

import pytest

from conesim.core import compiled
from tests.child_process import python
from tests.core.demo_kernels import edit, run, write_package


def notice(cores: int = 1, *, cached: bool = True) -> str:
    """The notice a process with ``cores`` cores prints."""
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(compiled, "_cores", lambda: cores)
        return compiled.notice(cached=cached)


def test_one_line_while_compiling_and_none_when_loading(tmp_path: Path) -> None:
    """A cold process prints the notice once (two kernels compiled), to stderr, not as a
    warning; a warm one prints nothing."""
    write_package(tmp_path)
    cold, err = run(tmp_path, "common.offset(1.0)", **{"PYTHONWARNINGS": "error"})
    assert cold["misses"] == {"chain": 1, "offset": 1}
    assert err.splitlines() == [notice()]
    warm, err = run(tmp_path, "common.offset(1.0)")
    assert warm["misses"] == {"chain": 0, "offset": 0}
    assert err == ""


def test_the_notice_without_a_cache_directory(tmp_path: Path) -> None:
    """No writable cache: the module warnings, and the notice says every run compiles."""
    write_package(tmp_path)
    action = "common.offset(1.0)"
    blocked = (
        "import numba.core.caching as caching\n"
        "def unwritable(self):\n"
        "    raise OSError('read-only')\n"
        "caching._CacheLocator.ensure_cache_path = unwritable\n"
    )
    script = blocked + "\n" + f"import sys; sys.path.insert(0, {str(tmp_path)!r})\n"
    script += "from ckdemo import chain, common\nchain.chain(3.0); " + action + "\n"
    lines = python(script).stderr.splitlines()
    assert notice(cached=False) in lines
    assert lines.count(notice(cached=False)) == 1
    assert sum("no writable cache directory" in line for line in lines) >= 3


SKIP_OWN_SHARE = (
    "from conesim.core import kernel_workers\n"
    "kernel_workers._compile_claimed = lambda calls, claims: True  # all to the helpers\n"
)
"""Leaves every kernel of a parallel warm-up to the helpers (this process compiles none)."""


def test_a_cold_parallel_warm_up_compiles_then_loads(tmp_path: Path) -> None:
    """Two cores, cold: the right value and one notice; warm again: loaded, no notice."""
    write_package(tmp_path)
    cold, err = run(tmp_path, "warm.warm_up()", cores=2)
    assert cold["value"] == 24.0
    assert err.splitlines() == [notice(2)]
    warm, err = run(tmp_path, "warm.warm_up()", cores=2)
    assert warm["value"] == 24.0
    assert warm["misses"] == {"chain": 0, "offset": 0}
    assert err == ""


def test_the_helpers_compile_every_kernel_the_warm_up_calls(tmp_path: Path) -> None:
    """With this process's share left to them, the helpers compile every kernel the
    warm-up calls (as Python, for its types): run again, the warm-up only loads. After an
    edit of a callee, likewise, and the value is the new one."""
    package = write_package(tmp_path)
    cold, err = run(tmp_path, SKIP_OWN_SHARE + "warm.warm_up()", cores=2)
    assert cold["misses"] == {"chain": 0, "offset": 0}
    assert cold["hits"] == {"chain": 1, "offset": 1}
    assert cold["value"] == 24.0
    assert err.splitlines() == [notice(2)]
    edit(package / "common.py", "x + 1.0", "x + 2.0")
    edited, _ = run(tmp_path, SKIP_OWN_SHARE + "warm.warm_up()", cores=2)
    assert edited["misses"] == {"chain": 0, "offset": 0}
    assert edited["value"] == (3.0 + 2.0) * 3.0 * 2.0


def test_one_core_or_busy_cores_compile_in_the_process(tmp_path: Path) -> None:
    """One core, or two with only one idle (other work on the other): no helpers; the
    warm-up goes on and compiles its kernels itself."""
    write_package(tmp_path)
    cold, _ = run(tmp_path, "warm.warm_up()", cores=1)
    assert cold["misses"] == {"chain": 1, "offset": 1}
    busy = "compiled._idle_cores = lambda: 1.2\n"
    edit(tmp_path / "ckdemo" / "common.py", "x + 1.0", "x + 2.0")
    again, err = run(tmp_path, SKIP_OWN_SHARE + busy + "warm.warm_up()", cores=2)
    assert again["misses"] == {"chain": 1, "offset": 1}
    assert again["value"] == (3.0 + 2.0) * 3.0 * 2.0
    assert err.splitlines() == [notice(2)]


@pytest.mark.slow
def test_the_planners_cold_warm_up_is_compiled_by_the_helpers(tmp_path: Path) -> None:
    """The planner's warm-up from a cold cache (its own ``NUMBA_CACHE_DIR``), all left to
    the helpers: the warm-up run as Python calls the kernels with the types the compiled
    warm-up uses, so the warm-up then loads every kernel and compiles none; one notice."""
    script = (
        SKIP_OWN_SHARE
        + """
import importlib, pkgutil
from conesim.core import compiled
compiled._cores = compiled._idle_cores = lambda: 2
from conesim.planner import kernel_chains, kernels
from conesim.planner.autopilot import warm_up_planner
warm_up_planner()
modules = [kernel_chains] + [importlib.import_module(f"conesim.planner.kernels.{m.name}")
                     for m in pkgutil.iter_modules(kernels.__path__)]
misses = {k: dict(v.stats.cache_misses) for m in modules for k, v in vars(m).items()
          if hasattr(v, "stats") and v.__module__ == m.__name__ and v.stats.cache_misses}
hits = sum(sum(v.stats.cache_hits.values()) for m in modules for v in vars(m).values()
           if hasattr(v, "stats"))
assert not misses, misses
assert hits >= 9, hits
print("ok")
"""
    )
    done = python(script, NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    assert done.stdout.strip() == "ok"
    assert done.stderr.splitlines() == [notice(2)]
