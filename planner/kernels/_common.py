"""What the kernel modules share: the station axis' wrap of a difference, a mask's rows.

Private to ``planner.kernels``: each helper is compiled once here and called
from the kernels of several modules. Their cached machine code follows an
edit here (``conesim.core.kernel_cache`` keys each kernel's cache by all the
code it reaches).
"""

from __future__ import annotations

import numpy as np

from conesim.core.compiled import cached_njit


def _probe() -> None:
    """Nothing: what ``cached_njit`` asks numba to cache, from this file's directory."""


# Cached beside this file (or under NUMBA_CACHE_DIR); with no writable cache
# directory, compiled in every process (a cold compile: see the package docstring).
_compiled = cached_njit(_probe, "conesim.planner.kernels._common")


@_compiled
def wrapped_difference(diff, length, closed):
    """A station difference ``diff`` [m] wrapped into [-length/2, length/2) when ``closed``.

    ``(x % length) - length / 2``, numpy's formulation (the reference in
    ``tests/planner/kernels/geometry_reference.py``), for one difference.

    With ``x = diff + length / 2``, Python's (and numpy's) float ``x % length``
    is ``fmod`` moved onto the divisor's sign; ``fmod`` is exact, and for x in
    [-length, 2 length) it is x, x (then + length) or x - length (exact by
    Sterbenz's lemma). Those cases are written out (``fmod`` is slow); a zero
    remainder is +0 as in Python. Anything else takes ``%``.
    """
    if closed and length > 0.0:
        x = diff + 0.5 * length
        if 0.0 < x < length:
            r = x
        elif -length <= x < 0.0:
            r = x + length
        elif length <= x < 2.0 * length:
            r = x - length
        elif x == 0.0:
            r = 0.0
        else:
            r = x % length
        return r - 0.5 * length
    return diff


@_compiled
def true_rows(mask):
    """``mask.nonzero()[0]``."""
    out = np.empty(len(mask), np.intp)
    m = 0
    for i in range(len(mask)):
        if mask[i]:
            out[m] = i
            m += 1
    return out[:m]
