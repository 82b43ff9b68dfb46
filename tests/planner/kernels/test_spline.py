"""The spline's sampling (``planner.kernels.spline``) is scipy's ``BSpline`` and
numpy's ``interp``, bit for bit."""

from __future__ import annotations

import numpy as np
from numpy.testing import assert_array_equal
from scipy.interpolate import BSpline, splev, splprep

from conesim.planner import MidlineConfig
from conesim.planner.geometry import arc_length
from conesim.planner.kernels.spline import _spline_at
from conesim.planner.spline import spline_through


def ref_spline_through(points: np.ndarray, config: MidlineConfig) -> np.ndarray | None:
    """``spline_through`` with scipy's ``BSpline`` and numpy's ``interp``."""
    m = len(points)
    degree = min(config.spline_degree, m - 1)
    length = float(arc_length(points)[-1])
    count = max(int(length * 2 / config.spacing) + 2, 2 * m)
    try:
        ((knots, coefficients, k), _), _, ier, _ = splprep(
            points.T, s=m * config.spline_sigma**2, k=degree, full_output=True
        )
        if ier > 0:
            return None
        spline = BSpline.construct_fast(knots, np.column_stack(coefficients), k)
        u = np.arange(count) * (1.0 / (count - 1))
        u[-1] = 1.0
        s = arc_length(spline(u))
        stations = np.arange(0.0, float(s[-1]), config.spacing)
        if s[-1] - stations[-1] > 1e-9:
            stations = np.concatenate([stations, s[-1:]])
        path = spline(np.interp(stations, s, u))
    except (ValueError, TypeError):
        return None
    return path if np.isfinite(path).all() else None


def test_spline_path_is_bspline_and_interp() -> None:
    """The compiled evaluation, arc length, stations and interp: scipy's and numpy's numbers."""
    rng = np.random.default_rng(26)
    config = MidlineConfig()
    for trial in range(300):
        m = int(rng.integers(2, 40))
        x = np.cumsum(rng.uniform(0.2, 3.0, m))
        y = np.cumsum(rng.normal(0.0, 0.8, m))
        points = np.column_stack([x, y])
        if trial % 7 == 0:
            points = np.round(points)
        expected = ref_spline_through(points, config)
        got = spline_through(points, config)
        if expected is None:
            assert got is None
        else:
            assert got is not None
            assert_array_equal(got, expected)


def test_spline_evaluation_is_splev_for_every_degree() -> None:
    """De Boor's recursion as scipy runs it: splev's numbers at knots, ends and inside."""
    rng = np.random.default_rng(27)
    work = np.empty(12)
    for trial in range(200):
        m = int(rng.integers(2, 25))
        points = np.vstack([np.cumsum(rng.uniform(1.0, 4.0, m)), rng.normal(0.0, 2.0, m)])
        k = min(int(rng.integers(1, 6)), m - 1)
        tck, _ = splprep(points, s=0.0 if trial % 2 else 0.05 * m, k=k)
        u = np.concatenate([[0.0, 1.0], tck[0], rng.uniform(0.0, 1.0, 30)])
        c = np.column_stack(tck[1])
        out = np.empty((len(u), 2))
        prev = k
        for i, x in enumerate(u):
            prev = _spline_at(tck[0], c, k, x, out, i, prev, work)
        assert_array_equal(out, np.column_stack(splev(u, tck)))
