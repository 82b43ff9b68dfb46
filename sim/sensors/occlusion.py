"""Occlusion of cones by nearer cones, seen from the sensor.

Cone i is hidden when its centre bearing lies within the angular half-width of
a nearer cone j::

    r_j < r_i   and   |wrap(b_i - b_j)| < asin(min(1, rho_j / r_j))

with rho_j the cone's base half-width (0.114 m small, 0.1425 m big). Every cone
in range occludes, whether or not it is itself detected; partial visibility is
not modelled (a cone is either hidden or not).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray


def occluded(
    ranges: NDArray[np.float64],
    bearings: NDArray[np.float64],
    radii: NDArray[np.float64],
    targets: NDArray[np.bool_],
) -> NDArray[np.bool_]:
    """Which of the target cones are hidden behind a nearer cone.

    Args:
        ranges: (n,) distances from the sensor [m].
        bearings: (n,) bearings in the sensor frame [rad], in [-pi, pi].
        radii: (n,) base half-widths [m].
        targets: (n,) the cones to test (e.g. those in the field of view);
            all n cones occlude.

    Returns:
        (n,) True where a target cone is hidden (False for non-targets).
    """
    hidden = np.zeros(ranges.shape, dtype=bool)
    t = np.flatnonzero(targets)
    if t.size == 0 or ranges.size < 2:
        return hidden
    half_width = np.arcsin(np.minimum(radii / np.maximum(ranges, 1e-12), 1.0))  # (n,) [rad]
    diff = np.abs(bearings[t, None] - bearings[None, :])  # (targets, n), in [0, 2 pi]
    diff = np.minimum(diff, 2.0 * np.pi - diff)
    nearer = ranges[None, :] < ranges[t, None]
    hidden[t] = np.any(nearer & (diff < half_width[None, :]), axis=1)
    return hidden
