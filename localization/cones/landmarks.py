"""The cone map the filter localizes against: positions, colour classes and a k-d tree."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Final

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

COLOUR_CLASS: Final = {"blue": 0, "yellow": 1, "orange": 2, "big_orange": 2, "unknown": -1}
"""A colour label's class: a big orange cone is orange; -1 says nothing."""


def colour_classes(labels: Sequence[str]) -> NDArray[np.intp]:
    """Each label's class (``COLOUR_CLASS``), (k,)."""
    return np.array([COLOUR_CLASS[label] for label in labels], dtype=np.intp)


class LandmarkMap:
    """Cone positions in ``reference`` with their colours, for association.

    Args:
        positions: (n, 2) [m] the cones as surveyed.
        colours: n labels from ``CONE_COLOURS`` (``unknown`` matches any colour),
            or their classes (``COLOUR_CLASS``'s values, an int array (n,)).

    Attributes:
        positions: (n, 2) [m], read-only.
        classes: (n,) colour classes (``COLOUR_CLASS``), read-only.
        tree: ``scipy.spatial.cKDTree`` over ``positions``.
    """

    def __init__(self, positions: ArrayLike, colours: Sequence[str] | NDArray[np.intp]) -> None:
        p = np.array(positions, dtype=float)
        if p.ndim != 2 or p.shape[1] != 2 or len(p) == 0:
            raise ValueError(f"LandmarkMap: positions must be (n, 2), n >= 1, got {p.shape}")
        if len(colours) != len(p):
            raise ValueError(f"LandmarkMap: {len(colours)} colours for {len(p)} cones")
        if isinstance(colours, np.ndarray):  # classes (a map being built, ``slam``)
            classes = np.array(colours, dtype=np.intp)
            if classes.ndim != 1 or not ((classes >= -1) & (classes <= 2)).all():
                raise ValueError("LandmarkMap: colour classes must be (n,) in -1..2")
        else:
            unknown = sorted(set(colours) - set(COLOUR_CLASS))
            if unknown:
                raise ValueError(
                    f"LandmarkMap: unknown colours {unknown}; allowed {list(COLOUR_CLASS)}"
                )
            classes = colour_classes(colours)
        p.setflags(write=False)
        self.positions = p
        self.classes = classes
        self.classes.setflags(write=False)
        self.tree = cKDTree(p)

    def __len__(self) -> int:
        return len(self.positions)
