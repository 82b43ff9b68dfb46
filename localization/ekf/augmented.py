"""The map's part of a state with static landmarks appended (EKF-SLAM, ``localization.slam``).

The state is the vehicle's (``localization.ekf.model``, n_v entries) followed
by 2 L landmark positions (east, north) in ``reference``::

    x = [x_v; x_m]                         (n_v + 2 L, 1)
    P = [[P_vv, P_vm], [P_mv, P_mm]]

The vehicle's part, x_v and P_vv, is filterpy's as in every mode (its
``predict`` and ``update``). The map's part is a :class:`MapState` beside
it, held in the compressed form of Guivant and Nebot's compressed EKF::

    P_mv = B T,      P_mm = M - B C B'

with B (2 L, n_v) and M (2 L, 2 L) fixed, and T, C (n_v, n_v) the steps
since B and M were last written out (T = I and C = 0 then, held as None).

Why: the filter runs ~190 messages a simulated second, and every late one
replays a few more; each keeps a snapshot of the state after it (the
history, ``localization.ekf.history``). Held densely, every IMU sample,
fix, heading and wheel speed made a new (n, n) P (n = n_v + 2 L, several
hundred): an O(n^2) copy per predict, and the full update's O(n^2) per
measurement: two thirds of the loop's time with a few hundred cones. In this form
those messages touch only n_v x n_v matrices (and x_m, O(L n_v)), and the
snapshots share B and M:

* predict (the landmarks do not move, f touches x_v only): filterpy's
  ``P_vv' = F P_vv F' + Q``, and ``P_mv' = P_mv F'``, so ``T' = T F'``;

* a vehicle measurement (GPS, heading, wheel speed: H = [H_v, 0]):
  filterpy's update of x_v and P_vv gives K_v and S^-1; the landmarks'
  gain is K_m = P_mv H_v' S^-1 = B G with G = T H_v' S^-1, so::

      x_m' = x_m + B G y,     T' = T (I - H_v' K_v'),     C' = C + G S G'

  and with the map frozen (the Schmidt, or consider, update: K_m = 0, the
  landmarks stay put and their uncertainty still counts) only T changes;

* a cone scan (:func:`scan_terms`, :func:`scan_update`): H has the
  vehicle's columns and those of the a matched landmarks only (s: their
  2 a entries of x_m), so P H' is::

      (P H')_v = P_vv H_v' + P_vs H_s',     (P H')_m = P_mv H_v' + P_ms H_s'

  O(L n_v a), and S = H P H' + R, the gain K = P H' S^-1 and the NIS
  follow. Then the standard form::

      x' = x + K y,   P_vv' = P_vv - K_v S K_v',   P_mv' = P_mv - K_m S K_v',
      P_mm' = P_mm - K_m S K_m'

  written out as B = P_mv', M = M - [B, K_m] [C B'; S K_m'] (T = I, C = 0):
  one symmetric product of O(L^2 (n_v + a)), the compiled
  ``kernels.downdated``, once a scan while the map is built. With the map
  frozen, K_m = 0 (the Schmidt update, its Joseph form): M and x_m stay,
  and only B = P_mv - (P H')_m K_v' is written, O(L n_v a). Not
  filterpy's ``update`` for a scan: it works on the dense (n, n) P, O(n^3)
  with its Joseph form (about 30 ms at 200 cones against well under 1 ms
  here), where H covers a few of P's columns only;

* a new landmark from a detection z (in the sensor frame, covariance R_z)
  seen from (p, yaw) with the sensor at o::

      m = p + R(yaw) (z + o)
      G_x = dm/d(p, yaw) = [I, (-(m - p)_y, (m - p)_x)]      G_z = R(yaw)
      P_mm = G_x P_pp G_x' + G_z R_z G_z',   P_mx = G_x P_p.

  Several detections of one scan are added together: they are correlated
  through the pose they share. The map's part is written out first and M
  grows by a copy, O(L^2), on the scans that confirm landmarks (lap 1);

* removing a landmark is marginalising it: its rows of B and x_m, its rows
  and columns of M go (T and C do not change).

The tests compare every step with the dense formulas
(``tests/localization/slam_reference.py``) to 1e-9.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from conesim.localization.ekf import kernels
from conesim.localization.ekf.model import YAW, X, Y

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]

POSE = [X, Y, YAW]


def _frozen(a: FloatArray) -> FloatArray:
    a.flags.writeable = False
    return a


def _downdated(m: FloatArray, u: FloatArray, v: FloatArray) -> FloatArray:
    """``m - u v`` for a symmetric ``u v``, exactly symmetric (``kernels.downdated``)."""
    return kernels.downdated(m, np.ascontiguousarray(u), np.ascontiguousarray(v))


class MapState(NamedTuple):
    """The landmarks' means and their covariance in the compressed form (module docstring).

    Immutable (arrays read-only): every step makes a new one, and the history's
    snapshots share them. A named tuple: cheap to build, one per message.

    Attributes:
        x: x_m, (2 L, 1) [m].
        b: B, (2 L, n_v).
        t: T, (n_v, n_v), or None for the identity.
        m: M, (2 L, 2 L) [m^2].
        c: C, (n_v, n_v), or None for zero.
    """

    x: FloatArray
    b: FloatArray
    t: FloatArray | None
    m: FloatArray
    c: FloatArray | None

    @classmethod
    def empty(cls, nv: int) -> MapState:
        """No landmarks, beside ``nv`` vehicle states."""
        return cls(
            _frozen(np.zeros((0, 1))), _frozen(np.zeros((0, nv))), None,
            _frozen(np.zeros((0, 0))), None,
        )  # fmt: skip

    @property
    def size(self) -> int:
        """Landmarks L."""
        return len(self.x) // 2

    def cross(self) -> FloatArray:
        """P_mv = B T, (2 L, n_v)."""
        return self.b if self.t is None else np.dot(self.b, self.t)

    def blocks(self) -> FloatArray:
        """Each landmark's own covariance, the 2x2 blocks of P_mm's diagonal, (L, 2, 2)."""
        n = self.size
        idx = np.arange(n)
        out = self.m.reshape(n, 2, n, 2)[idx, :, idx, :]
        if self.c is None:
            return out
        bj = self.b.reshape(n, 2, -1)
        return out - np.matmul(np.matmul(bj, self.c), bj.transpose(0, 2, 1))

    def columns(self, rows: IntArray) -> FloatArray:
        """P_mm's columns ``rows`` (indices into x_m), (2 L, len(rows))."""
        out = self.m[:, rows]
        if self.c is None:
            return out
        return out - np.dot(self.b, np.dot(self.c, self.b[rows].T))

    def folded(self) -> MapState:
        """The same covariance written out: B = P_mv, M = P_mm (re-symmetrised), T = I, C = 0."""
        if self.t is None and self.c is None:
            return self
        m = self.m
        if self.c is not None:
            m = _frozen(_downdated(m, self.b, np.dot(self.c, self.b.T)))
        return MapState(self.x, _frozen(self.cross()), None, m, None)


def dense(xv: FloatArray, pvv: FloatArray, ms: MapState) -> tuple[FloatArray, FloatArray]:
    """The whole state and covariance, (n, 1) and (n, n) (for inspection and the tests)."""
    nv = len(xv)
    full = ms.folded()
    n = nv + len(ms.x)
    p = np.empty((n, n))
    p[:nv, :nv] = pvv
    p[nv:, :nv] = full.b
    p[:nv, nv:] = full.b.T
    p[nv:, nv:] = full.m
    return np.vstack([xv, ms.x]), p


def predicted(ms: MapState, f: FloatArray) -> MapState:
    """The map's part after filterpy's predict with F over the vehicle (``T' = T F'``;
    ``f`` may be overwritten later: T is a new array)."""
    if not len(ms.x):
        return ms
    t = f.T.copy() if ms.t is None else np.dot(ms.t, f.T)
    return MapState(ms.x, ms.b, t, ms.m, ms.c)  # cheaper than ``_replace``


def measured(
    ms: MapState,
    h: FloatArray,
    gain: FloatArray,
    s_inv: FloatArray,
    y: FloatArray,
    *,
    frozen: bool,
) -> MapState:
    """The map's part after filterpy's update of the vehicle with a vehicle measurement.

    Args:
        ms: the map's part before it.
        h: H_v, (m, n_v).
        gain: filterpy's K_v, (n_v, m).
        s_inv: its S^-1, (m, m).
        y: the residual, (m, 1).
        frozen: the map is frozen (Schmidt): the landmarks do not move.
    """
    if not len(ms.x):
        return ms
    t0 = ms.t
    if t0 is None:  # T = I: T H_v' is H_v'
        th = h.T
        t = np.negative(np.dot(th, gain.T))
        t.ravel()[:: len(t) + 1] += 1.0  # 1 - (H_v' K_v')_ii, as I - H_v' K_v'
    else:
        th = np.dot(t0, h.T)  # T H_v', (n_v, m)
        t = t0 - np.dot(th, gain.T)  # the same rounding as -(T H_v' K_v') + T
    if frozen:
        return MapState(ms.x, ms.b, t, ms.m, ms.c)
    g = np.dot(th, s_inv)  # G = T H_v' S^-1
    x = ms.x + np.dot(ms.b, np.dot(g, y))
    x.flags.writeable = False
    gsg = np.dot(g, th.T)  # G S G' = T H_v' S^-1 H_v T'
    return MapState(x, ms.b, t, ms.m, gsg if ms.c is None else ms.c + gsg)


def entries(landmarks: IntArray) -> IntArray:
    """The indices into x_m of landmarks ``landmarks`` (a,): each one's east and north, (2a,)."""
    return (2 * landmarks[:, None] + np.arange(2)).reshape(-1)


class ScanTerms(NamedTuple):
    """P H' and S of a scan whose H covers the vehicle and some landmarks (:func:`scan_terms`).

    Attributes:
        pht_v: the vehicle's rows of P H', (n_v, m).
        pht_m: the landmarks' rows, (2 L, m).
        s: H P H' + R, (m, m).
        cross: P_mv before the scan, (2 L, n_v).
    """

    pht_v: FloatArray
    pht_m: FloatArray
    s: FloatArray
    cross: FloatArray


def scan_terms(
    pvv: FloatArray, ms: MapState, h: FloatArray, rows: IntArray, r: FloatArray
) -> ScanTerms:
    """P H' and S of a measurement of the vehicle and the landmarks ``rows``.

    Args:
        pvv: P_vv, (n_v, n_v).
        ms: the map's part.
        h: H over the vehicle's columns, then over x_m's entries ``rows`` in
            that order, (m, n_v + len(rows)).
        rows: indices into x_m, (k,).
        r: the measurement's covariance, (m, m).
    """
    nv = len(pvv)
    hv, hs = h[:, :nv], h[:, nv:]
    cross = ms.cross()
    pht_v = np.dot(pvv, hv.T) + np.dot(cross[rows].T, hs.T)
    pht_m = np.dot(cross, hv.T) + np.dot(ms.columns(rows), hs.T)
    s = np.dot(hv, pht_v) + np.dot(hs, pht_m[rows]) + r
    return ScanTerms(pht_v, pht_m, s, cross)


def scan_update(
    xv: FloatArray, pvv: FloatArray, ms: MapState, y: FloatArray, terms: ScanTerms, *, frozen: bool
) -> tuple[FloatArray, FloatArray, MapState]:
    """(x_v, P_vv, the map's part) after the scan of :func:`scan_terms` (module docstring).

    Args:
        frozen: the map is frozen: the Schmidt update (the landmarks' gain is zero).
    """
    s_inv = np.linalg.inv(terms.s)
    kv = np.dot(terms.pht_v, s_inv)
    xv1 = xv + np.dot(kv, y)
    pvv1 = pvv - np.dot(kv, terms.pht_v.T)  # the filter re-symmetrises it
    if frozen:
        full = ms if ms.c is None else ms.folded()
        b = _frozen(terms.cross - np.dot(terms.pht_m, kv.T))
        return xv1, pvv1, MapState(ms.x, b, None, full.m, None)
    km = np.dot(terms.pht_m, s_inv)
    b = _frozen(terms.cross - np.dot(km, terms.pht_v.T))
    x = _frozen(ms.x + np.dot(km, y))
    if ms.c is None:
        m = _downdated(ms.m, km, terms.pht_m.T)
    else:  # M - B C B' - K_m S K_m' in one pass
        u = np.hstack([ms.b, km])
        w = np.vstack([np.dot(ms.c, ms.b.T), terms.pht_m.T])
        m = _downdated(ms.m, u, w)
    return xv1, pvv1, MapState(x, b, None, _frozen(m), None)


def add_landmarks(
    xv: FloatArray,
    pvv: FloatArray,
    ms: MapState,
    points: FloatArray,
    cov: FloatArray,
    *,
    offset: tuple[float, float],
) -> MapState:
    """The map's part with a landmark appended for each detection (module docstring).

    Args:
        xv: the vehicle's state, (n_v, 1).
        pvv: its covariance, (n_v, n_v).
        ms: the map's part.
        points: the detections in the sensor frame, (k, 2) [m].
        cov: their covariances there, (k, 2, 2) [m^2].
        offset: the sensor's planar origin in the antenna frame [m].
    """
    k = len(points)
    yaw = xv.item(YAW)
    c, s = math.cos(yaw), math.sin(yaw)
    rot = np.array([[c, -s], [s, c]])
    rel = (points + np.asarray(offset)) @ rot.T  # m - p, (k, 2)
    pos = rel + np.array([xv.item(X), xv.item(Y)])
    g3 = np.zeros((k, 2, 3))
    g3[:, 0, 0] = g3[:, 1, 1] = 1.0
    g3[:, 0, 2], g3[:, 1, 2] = -rel[:, 1], rel[:, 0]
    gx = g3.reshape(2 * k, 3)
    full = ms.folded()
    cross_v = np.dot(gx, pvv[POSE])  # the new rows of P_mv, (2k, n_v)
    cross_m = np.dot(gx, full.b[:, POSE].T)  # with the old landmarks, (2k, 2L)
    block = np.dot(cross_v[:, POSE], gx.T)
    rz = np.einsum("ij,qjk,lk->qil", rot, cov, rot)
    idx = np.arange(k)
    block.reshape(k, 2, k, 2)[idx, :, idx, :] += rz
    n = len(ms.x)
    m = np.empty((n + 2 * k, n + 2 * k))
    m[:n, :n] = full.m
    m[n:, :n] = cross_m
    m[:n, n:] = cross_m.T
    m[n:, n:] = kernels.symmetrised(block)
    x = np.vstack([ms.x, pos.reshape(-1, 1)])
    return MapState(_frozen(x), _frozen(np.vstack([full.b, cross_v])), None, _frozen(m), None)


def remove_landmarks(ms: MapState, drop: IntArray) -> MapState:
    """The map's part without landmarks ``drop`` (indices): marginalised."""
    keep = np.ones(len(ms.x), dtype=bool)
    keep[2 * drop] = keep[2 * drop + 1] = False
    return MapState(
        _frozen(ms.x[keep]), _frozen(ms.b[keep]), ms.t, _frozen(ms.m[np.ix_(keep, keep)]), ms.c
    )
