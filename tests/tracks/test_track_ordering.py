"""Ordering the cones of one boundary: short tours through shuffled cones."""

from __future__ import annotations

import numpy as np
import pytest

from conesim.tracks.ordering import order_loop, order_path


def is_cyclic_order(tour: np.ndarray, n: int) -> bool:
    """Whether ``tour`` visits 0..n-1 in order (either way round, any start)."""
    steps = np.diff(np.concatenate([tour, tour[:1]])) % n
    return bool(np.all(steps == 1) or np.all(steps == n - 1))


@pytest.mark.parametrize("seed", range(5))
def test_loop_order_survives_shuffling(points, seed: int) -> None:
    """A hairpin-shaped boundary (legs 3 m apart, cones 3 m apart), shuffled."""
    loop = points(40.0, 1.5, 3.0)
    perm = np.random.default_rng(seed).permutation(len(loop))
    tour = perm[order_loop(loop[perm])]
    assert is_cyclic_order(tour, len(loop))


@pytest.mark.parametrize("seed", range(5))
def test_path_order_of_a_shuffled_lane(seed: int) -> None:
    """Cones along an S-shaped lane come back in order, from one end to the other."""
    s = np.linspace(0.0, 60.0, 25)
    lane = np.column_stack([s, 4.0 * np.sin(s / 10.0)])
    perm = np.random.default_rng(seed).permutation(len(lane))
    path = perm[order_path(lane[perm])]
    assert list(path) in (list(range(25)), list(range(24, -1, -1)))


def test_tiny_inputs() -> None:
    """Three cones or fewer: any order is a tour."""
    pts = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    assert sorted(order_loop(pts)) == [0, 1, 2]
    assert sorted(order_path(pts[:2])) == [0, 1]
