"""Cone geometry and a spatial index of the cones on the track.

``ConeMap`` keeps the cones' positions, kinds and a ``scipy.spatial.cKDTree``
over them. Cones get knocked, so the world calls ``update(positions)`` with the
current positions (a copy, cheap enough for every physics step); the tree is
rebuilt only when some cone has moved more than ``tolerance`` from where the
tree has it (checked lazily at the next ``query``), and ``query`` widens its
search by ``tolerance`` and then filters on the current positions, so answers
are always exact. A detector's cost then grows with the cones in range, not with
the length of the track.

Cone sizes (REFERENCES.md, FSG handbook, marked "check"): small cone base
228 x 228 mm, 325 mm high; big (orange) cone base 285 x 285 mm, 505 mm high.
The occlusion radius is half the base width.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

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
    """Cone positions and kinds with a k-d tree for range queries.

    Args:
        positions: (n, 2) cone positions in ``reference`` [m].
        kinds: n kinds from ``CONE_COLOURS``.
        tolerance: displacement that triggers a rebuild of the tree [m], > 0.

    Attributes:
        kinds: the n kinds.
        radii: (n,) base half-widths [m].
        heights: (n,) cone heights [m].
        codes: (n,) index of each kind in ``CONE_COLOURS``.
        rebuilds: how many times the tree was built (1 after construction).
    """

    def __init__(
        self, positions: ArrayLike, kinds: tuple[str, ...], tolerance: float = 0.05
    ) -> None:
        p = as_positions(positions, "ConeMap")
        check_kinds(tuple(kinds), len(p), "ConeMap")
        if not tolerance > 0.0:
            raise ValueError(f"ConeMap.tolerance = {tolerance!r} is out of range: allowed (0, inf)")
        self.kinds = tuple(kinds)
        self.radii = cone_radii(self.kinds)
        self.heights = cone_heights(self.kinds)
        self.codes = kind_codes(self.kinds)
        self.tolerance = tolerance
        self.rebuilds = 0
        self._positions = p.copy()
        self._checked = True
        self._build()

    def _build(self) -> None:
        self._tree_positions = self._positions.copy()
        self._tree = cKDTree(self._tree_positions)
        self.rebuilds += 1

    @property
    def positions(self) -> NDArray[np.float64]:
        """Current (n, 2) positions [m] (read-only view)."""
        view = self._positions.view()
        view.flags.writeable = False
        return view

    def __len__(self) -> int:
        return len(self._positions)

    def update(self, positions: ArrayLike) -> None:
        """Record the current positions (same cones, same order), (n, 2) [m].

        O(n) copy only: the displacement check, and a rebuild of the tree if
        some cone moved more than ``tolerance``, wait for the next ``query``.
        """
        p = as_positions(positions, "ConeMap.update")
        if p.shape != self._positions.shape:
            raise ValueError(f"ConeMap.update: expected {self._positions.shape}, got {p.shape}")
        self._positions = p.copy()
        self._checked = False

    def _refresh(self) -> None:
        """Rebuild the tree if a cone moved more than ``tolerance`` since the last build."""
        moved2 = np.max(np.sum((self._positions - self._tree_positions) ** 2, axis=1), initial=0.0)
        if moved2 > self.tolerance**2:
            self._build()
        self._checked = True

    def query(self, center: ArrayLike, radius: float) -> NDArray[np.intp]:
        """Indices of the cones within ``radius`` [m] of ``center`` (2,), ascending."""
        if not self._checked:
            self._refresh()
        c = np.asarray(center, dtype=float)
        idx = np.asarray(self._tree.query_ball_point(c, radius + self.tolerance), dtype=np.intp)
        if idx.size == 0:
            return idx
        idx.sort()
        d2 = np.sum((self._positions[idx] - c) ** 2, axis=1)
        return idx[d2 <= radius * radius]
