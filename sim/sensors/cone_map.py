"""Cone geometry and the cones on the track, with a range query.

``ConeMap`` keeps the cones' positions and kinds, with each kind's radius,
height and colour code worked out once. Cones get knocked, so the world calls
``update(positions)`` with the current positions (a copy, cheap enough for
every physics step a cone moves). ``query`` tests every cone's squared
distance in one vectorised pass: on a Formula Student track of a few hundred
cones that is cheaper than a spatial index's query, and there is no index to
rebuild while a knocked cone slides. Answers are exact on the current
positions.

Cone sizes (REFERENCES.md, FSG handbook, marked "check"): small cone base
228 x 228 mm, 325 mm high; big (orange) cone base 285 x 285 mm, 505 mm high.
The occlusion radius is half the base width.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from conesim.core.messages import CONE_COLOURS

SMALL_CONE_RADIUS = 0.114  # [m] half of the 228 mm base (FSG handbook)
BIG_CONE_RADIUS = 0.1425  # [m] half of the 285 mm base (FSG handbook)
SMALL_CONE_HEIGHT = 0.325  # [m] (FSG handbook)
BIG_CONE_HEIGHT = 0.505  # [m] (FSG handbook)
BIG_KIND = "big_orange"


def cone_radii(kinds: tuple[str, ...] | list[str]) -> NDArray[np.float64]:
    """Base half-width of each cone [m], shape (n,)."""
    return np.array([BIG_CONE_RADIUS if k == BIG_KIND else SMALL_CONE_RADIUS for k in kinds])


def cone_heights(kinds: tuple[str, ...] | list[str]) -> NDArray[np.float64]:
    """Height of each cone [m], shape (n,)."""
    return np.array([BIG_CONE_HEIGHT if k == BIG_KIND else SMALL_CONE_HEIGHT for k in kinds])


def kind_codes(kinds: tuple[str, ...] | list[str]) -> NDArray[np.intp]:
    """Index of each kind in ``CONE_COLOURS``, shape (n,)."""
    return np.array([CONE_COLOURS.index(k) for k in kinds], dtype=np.intp)


def check_kinds(kinds: tuple[str, ...], n: int, owner: str) -> None:
    """Require n kinds, each one of ``CONE_COLOURS``."""
    if len(kinds) != n:
        raise ValueError(f"{owner}: {len(kinds)} cone kinds for {n} positions")
    bad = sorted(set(kinds) - set(CONE_COLOURS))
    if bad:
        raise ValueError(f"{owner}: unknown cone kinds {bad}; allowed {CONE_COLOURS}")


def as_positions(positions: ArrayLike, owner: str) -> NDArray[np.float64]:
    """Positions as a float (n, 2) array, or a ValueError naming ``owner``."""
    p = np.asarray(positions, dtype=float)
    if p.ndim != 2 or p.shape[1] != 2:
        raise ValueError(f"{owner}: cone positions must be (n, 2), got {p.shape}")
    return p


class ConeMap:
    """Cone positions and kinds with a range query.

    Args:
        positions: (n, 2) cone positions in ``reference`` [m].
        kinds: n kinds from ``CONE_COLOURS``.

    Attributes:
        kinds: the n kinds.
        radii: (n,) base half-widths [m].
        heights: (n,) cone heights [m].
        codes: (n,) index of each kind in ``CONE_COLOURS``.
    """

    def __init__(self, positions: ArrayLike, kinds: tuple[str, ...]) -> None:
        p = as_positions(positions, "ConeMap")
        check_kinds(tuple(kinds), len(p), "ConeMap")
        self.kinds = tuple(kinds)
        self.radii = cone_radii(self.kinds)
        self.heights = cone_heights(self.kinds)
        self.codes = kind_codes(self.kinds)
        self._positions = p.copy()
        self._x = self._positions[:, 0]  # views: current after every update
        self._y = self._positions[:, 1]

    @property
    def positions(self) -> NDArray[np.float64]:
        """Current (n, 2) positions [m] (a read-only view; later updates show through it)."""
        view = self._positions.view()
        view.flags.writeable = False
        return view

    def __len__(self) -> int:
        return len(self._positions)

    def update(self, positions: ArrayLike) -> None:
        """Record the current positions (same cones, same order), (n, 2) [m]: an O(n)
        copy into the map's own array (the world calls it each step a cone moved)."""
        p = np.asarray(positions, dtype=float)
        if p.shape != self._positions.shape:
            raise ValueError(f"ConeMap.update: expected {self._positions.shape}, got {p.shape}")
        np.copyto(self._positions, p)

    def query(self, center: ArrayLike, radius: float) -> NDArray[np.intp]:
        """Indices of the cones within ``radius`` [m] of ``center`` (2,), ascending.

        A cone is in range when dx^2 + dy^2 <= radius^2 (the squares and the
        sum in that order, as ``np.sum((p - c) ** 2, axis=1)`` takes them).
        """
        cx, cy = np.asarray(center, dtype=float).tolist()
        dx = self._x - cx
        dy = self._y - cy
        dx *= dx
        dy *= dy
        dx += dy
        return np.flatnonzero(dx <= radius * radius)
