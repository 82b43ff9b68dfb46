"""Python's ``min`` and ``max`` of two floats, for the simulator's numba kernels.

numba's own ``min`` and ``max`` may answer differently where Python's keep
the first argument: on ties (``min(0.0, -0.0)`` is ``0.0``) and with NaN.
The kernels of ``sim.tyres``, ``sim.vehicle_dynamics`` and ``sim.progress``
use these, so that their numbers are the Python formulation's bit for bit.
"""

from __future__ import annotations

from conesim.core.compiled import cached_njit


def _probe() -> None:
    """Nothing: what ``cached_njit`` asks numba to cache, from this file's directory."""


_compiled = cached_njit(_probe, "conesim.sim.kernel_math")


@_compiled
def py_min(a, b):
    """Python's ``min(a, b)``: ``b`` only when it is smaller (ties and NaN keep ``a``)."""
    return b if b < a else a


@_compiled
def py_max(a, b):
    """Python's ``max(a, b)``: ``b`` only when it is larger (ties and NaN keep ``a``)."""
    return b if b > a else a
