"""Polyline helpers: arc length, resampling, splines, projection, crossings.

A polyline is an (n, 2) array of points [m]; ``closed`` says whether the last
point joins the first (a closed polyline never repeats its first point).
"""

from __future__ import annotations

import warnings

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import splev, splprep

from conesim.tracks.errors import TrackGeometryError

FloatArray = NDArray[np.float64]

_CHUNK = 1_000_000  # query x segment pairs per chunk in brute-force projection and crossings
MAX_SAMPLES = 250_000  # a dense curve of more samples (5 km at 2 cm) is not a cone track


def ring(points: FloatArray, closed: bool) -> FloatArray:
    """The vertices with the first one repeated at the end if ``closed``."""
    return np.vstack([points, points[:1]]) if closed else points


def cumulative_length(points: FloatArray, closed: bool) -> FloatArray:
    """Arc length at each vertex of :func:`ring` [m], starting at 0."""
    steps = np.hypot(*np.diff(ring(points, closed), axis=0).T)
    return np.concatenate([[0.0], np.cumsum(steps)])


def interpolate_at(points: FloatArray, closed: bool, s: FloatArray) -> FloatArray:
    """Points at arc lengths ``s`` [m] along the polyline, linear in between.

    Closed polylines wrap ``s`` modulo their length; open ones clamp it.
    """
    pts = ring(points, closed)
    cum = cumulative_length(points, closed)
    query = np.mod(s, cum[-1]) if closed else np.clip(s, 0.0, cum[-1])
    return np.column_stack([np.interp(query, cum, pts[:, 0]), np.interp(query, cum, pts[:, 1])])


def resample(points: FloatArray, closed: bool, spacing: float, start_s: float = 0.0) -> FloatArray:
    """Points evenly spaced about ``spacing`` [m] apart along the polyline.

    A closed polyline gets round(L / spacing) points starting at arc length
    ``start_s``, so the gap from the last back to the first equals the others;
    an open one keeps both end points.
    """
    total = float(cumulative_length(points, closed)[-1])
    if closed:
        count = max(3, round(total / spacing))
        s = start_s + np.arange(count, dtype=np.float64) * (total / count)
    else:
        count = max(2, round(total / spacing) + 1)
        s = np.linspace(0.0, total, count).astype(np.float64)
    return interpolate_at(points, closed, s)


def spline_curve(points: FloatArray, closed: bool, step: float, sigma: float = 0.0) -> FloatArray:
    """A cubic B-spline through (or, with ``sigma`` > 0, near) the points, sampled densely.

    Args:
        points: (n, 2) ordered points [m], no two consecutive ones equal.
        closed: fit a periodic spline.
        step: approximate spacing of the returned samples [m].
        sigma: allowed RMS distance of the spline from the points [m]; 0
            interpolates them (``splprep`` smoothing s = n * sigma^2).

    Returns:
        (m, 2) samples along the spline [m] (a closed curve does not repeat
        its first sample).

    Raises:
        TrackGeometryError: too few or degenerate points.
    """
    pts = _drop_repeats(points, closed)
    if len(pts) < 3:
        raise TrackGeometryError(
            f"a boundary or centreline needs at least 3 distinct points, got {len(pts)}"
        )
    data = ring(pts, closed)
    k = min(3, len(data) - 1)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # fitpack's "maxit reached" is harmless here
            tck, _ = splprep(data.T, s=len(data) * sigma**2, k=k, per=int(closed), quiet=1)
    except (ValueError, TypeError, ArithmeticError) as exc:
        raise TrackGeometryError(f"cannot fit a spline through the points: {exc}") from None
    length = float(cumulative_length(pts, closed)[-1])
    count = max(8, int(np.ceil(length / step)))
    if count > MAX_SAMPLES:
        raise TrackGeometryError(
            f"a boundary or centreline of {length:.0f} m is too long for a cone track"
        )
    u = np.linspace(0.0, 1.0, count + 1 if closed else count)
    curve = np.column_stack(splev(u, tck))
    if closed:
        curve = curve[:-1]
    if not np.all(np.isfinite(curve)):
        raise TrackGeometryError("spline fit through the points is not finite")
    return curve


def _drop_repeats(points: FloatArray, closed: bool, tol: float = 1e-6) -> FloatArray:
    """Remove points closer than ``tol`` [m] to the previous one."""
    keep = np.ones(len(points), dtype=bool)
    keep[1:] = np.hypot(*np.diff(points, axis=0).T) > tol
    pts = points[keep]
    if closed and len(pts) > 1 and np.hypot(*(pts[-1] - pts[0])) <= tol:
        pts = pts[:-1]
    return pts


def project(
    points: FloatArray, closed: bool, query: FloatArray, extend_ends: bool = False
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Nearest point on the polyline for each query point (exact, brute force).

    Args:
        points: (n, 2) polyline [m].
        closed: whether it is a loop.
        query: (q, 2) points [m].
        extend_ends: for an open polyline, extend the first and last segments
            to infinity (for points beyond its ends).

    Returns:
        ``s`` (q,) arc length of the foot point [m] (negative or beyond the
        length when extended), ``lateral`` (q,) signed distance, left of the
        direction of travel positive [m], and ``foot`` (q, 2) [m].
    """
    pts = ring(points, closed)
    a, d = pts[:-1], np.diff(pts, axis=0)
    seg_len2 = np.maximum(np.einsum("ij,ij->i", d, d), 1e-18)
    cum = cumulative_length(points, closed)
    q = np.asarray(query, dtype=float).reshape(-1, 2)
    s_out, lat_out, foot_out = np.empty(len(q)), np.empty(len(q)), np.empty((len(q), 2))
    lo = np.zeros(len(a))
    hi = np.ones(len(a))
    if extend_ends and not closed:
        lo[0], hi[-1] = -np.inf, np.inf
    chunk = max(1, _CHUNK // max(1, len(a)))
    for start in range(0, len(q), chunk):
        qc = q[start : start + chunk]
        rel = qc[:, None, :] - a[None, :, :]
        t = np.clip(np.einsum("qij,ij->qi", rel, d) / seg_len2, lo, hi)
        foot = a[None] + t[..., None] * d[None]
        dist2 = np.sum((qc[:, None, :] - foot) ** 2, axis=2)
        best = np.argmin(dist2, axis=1)
        rows = np.arange(len(qc))
        f = foot[rows, best]
        seg = d[best]
        cross = seg[:, 0] * (qc[:, 1] - f[:, 1]) - seg[:, 1] * (qc[:, 0] - f[:, 0])
        s_out[start : start + chunk] = cum[best] + t[rows, best] * np.sqrt(seg_len2[best])
        lat_out[start : start + chunk] = np.sign(cross) * np.sqrt(dist2[rows, best])
        foot_out[start : start + chunk] = f
    return s_out, lat_out, foot_out


def signed_area(points: FloatArray) -> float:
    """Signed area of the closed polygon [m^2]: positive when counter-clockwise."""
    x, y = points[:, 0], points[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def tangents(points: FloatArray, closed: bool) -> FloatArray:
    """(n, 2) unit tangents by central differences (one-sided at open ends)."""
    if closed:
        d = np.roll(points, -1, axis=0) - np.roll(points, 1, axis=0)
    else:
        d = np.gradient(points, axis=0)
    norm = np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-12)
    return d / norm[:, None]


def curvature(points: FloatArray, closed: bool) -> FloatArray:
    """(n,) signed curvature [1/m], positive turning left, from heading changes.

    Each value is the heading change across the neighbouring segments divided
    by their mean length (open ends repeat their neighbour's value).
    """
    pts = ring(points, closed)
    d = np.diff(pts, axis=0)
    heading = np.arctan2(d[:, 1], d[:, 0])
    length = np.hypot(d[:, 0], d[:, 1])
    if closed:
        turn = np.angle(np.exp(1j * (heading - np.roll(heading, 1))))
        return turn / np.maximum(0.5 * (length + np.roll(length, 1)), 1e-9)
    turn = np.angle(np.exp(1j * np.diff(heading)))
    inner = turn / np.maximum(0.5 * (length[1:] + length[:-1]), 1e-9)
    if len(inner) == 0:
        return np.zeros(len(points))
    return np.concatenate([inner[:1], inner, inner[-1:]])


def segment_crossings(
    a: FloatArray, closed_a: bool, b: FloatArray | None = None, closed_b: bool = False
) -> list[tuple[int, int]]:
    """Pairs of properly intersecting segments, within ``a`` or between ``a`` and ``b``.

    Args:
        a: (n, 2) polyline [m].
        closed_a: whether ``a`` is a loop.
        b: a second polyline; None checks ``a`` against itself, skipping
            segments that share a vertex.
        closed_b: whether ``b`` is a loop.

    Returns:
        (i, j) segment index pairs whose interiors cross.
    """
    pa = ring(a, closed_a)
    pb = pa if b is None else ring(b, closed_b)
    p, r = pa[:-1], np.diff(pa, axis=0)
    q, s = pb[:-1], np.diff(pb, axis=0)
    found: list[tuple[int, int]] = []
    rows = max(1, _CHUNK // max(1, len(q)))
    for start in range(0, len(p), rows):
        i, j = _crossing_pairs(p[start : start + rows], r[start : start + rows], q, s)
        i = i + start
        if b is None:
            keep = j > i + 1
            if closed_a:
                keep &= ~((i == 0) & (j == len(p) - 1))
            i, j = i[keep], j[keep]
        found += [(int(a_), int(b_)) for a_, b_ in zip(i, j, strict=True)]
    return found


def _crossing_pairs(
    p: FloatArray, r: FloatArray, q: FloatArray, s: FloatArray
) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """Index pairs (i, j) where segment p_i + t r_i properly crosses q_j + u s_j."""
    rxs = r[:, None, 0] * s[None, :, 1] - r[:, None, 1] * s[None, :, 0]
    qp = q[None, :, :] - p[:, None, :]
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        t = (qp[..., 0] * s[None, :, 1] - qp[..., 1] * s[None, :, 0]) / rxs
        u = (qp[..., 0] * r[:, None, 1] - qp[..., 1] * r[:, None, 0]) / rxs
    eps = 1e-9
    hit = (np.abs(rxs) > 1e-12) & (t > eps) & (t < 1 - eps) & (u > eps) & (u < 1 - eps)
    i, j = np.nonzero(hit)
    return i.astype(np.intp), j.astype(np.intp)
