"""The Kalman steps of a state with static landmarks appended (EKF-SLAM, ``localization.slam``).

The state is the vehicle's (``localization.ekf.model``, n_v entries) followed
by 2 L landmark positions (east, north) in ``reference``::

    x = [x_v; m_0; ...; m_{L-1}]           (n_v + 2 L, 1)
    P = [[P_vv, P_vm], [P_mv, P_mm]]

Why not filterpy's ``predict`` and ``update`` here: both are dense, O(n^3)
(``F P F'``, and the Joseph form ``(I - K H) P (I - K H)'``); at 200 cones
(n = 410) one filterpy update takes about 30 ms on this machine against
0.4 ms for the form below, and the filter runs ~190 of them a simulated
second plus replays. The structure makes both steps O(n^2 m) or less:

* predict: the landmarks do not move, so f only touches x_v::

      x_v' = f(x_v, u, dt),   P_vv' = F P_vv F' + Q,   P_vm' = F P_vm,   P_mm' = P_mm

* update (the standard form, then re-symmetrised; H has m rows)::

      S = H P H' + R,   K = P H' S^-1,   x' = x + K y,   P' = P - K S K'

  where H may cover only the first columns (a GPS fix sees x_v only); once
  the map is frozen, the landmarks' gain is zero (a Schmidt, or consider,
  update): they stay put, and their uncertainty still counts.

* a new landmark from a detection z (in the sensor frame, covariance R_z)
  seen from (p, yaw) with the sensor at o::

      m = p + R(yaw) (z + o)
      G_x = dm/d(p, yaw) = [I, (-(m - p)_y, (m - p)_x)]      G_z = R(yaw)
      P_mm = G_x P_pp G_x' + G_z R_z G_z',   P_mx = G_x P_p.

  Several detections of one scan are added together: they are correlated
  through the pose they share.

* removing a landmark is marginalising it: its rows and columns go.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from conesim.localization.ekf import kernels
from conesim.localization.ekf.model import YAW, X, Y

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]


def predict(
    x: FloatArray, p: FloatArray, xv_next: FloatArray, f: FloatArray, q: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """x and P after the motion step (module docstring); new arrays, P exactly symmetric.

    Args:
        x: the state, (n, 1).
        p: its covariance, (n, n).
        xv_next: f(x_v, u, dt), (n_v, 1).
        f: F over the vehicle's states, (n_v, n_v).
        q: Q over them, (n_v, n_v).
    """
    nv = len(xv_next)
    x1 = np.empty_like(x)
    x1[:nv] = xv_next
    x1[nv:] = x[nv:]
    p1 = np.empty_like(p)
    top = np.dot(f, p[:nv])  # F [P_vv, P_vm]
    p1[:nv, :nv] = kernels.symmetrised(np.dot(top[:, :nv], f.T) + q)
    p1[:nv, nv:] = top[:, nv:]
    p1[nv:, :nv] = top[:, nv:].T
    p1[nv:, nv:] = p[nv:, nv:]
    return x1, p1  # symmetric: the blocks off the diagonal are each other's transpose


def update(
    x: FloatArray,
    p: FloatArray,
    y: FloatArray,
    h: FloatArray,
    r: FloatArray,
    *,
    fixed: int | None = None,
) -> tuple[FloatArray, FloatArray]:
    """x and P after a measurement (module docstring); new arrays, P re-symmetrised.

    Args:
        x: the state, (n, 1).
        p: its covariance, (n, n).
        y: the residual z - h(x), (m, 1).
        h: H over the first k <= n states, (m, k).
        r: the measurement's covariance, (m, m).
        fixed: the states from this index on are held (a frozen map): their
            gain is zero, the Schmidt (consider) update, so they do not move
            while their uncertainty still enters S and the pose's covariance.
    """
    k = h.shape[1]
    pht = np.dot(p[:, :k], h.T)
    s = np.dot(h, pht[:k]) + r
    gain = np.linalg.solve(s, pht.T).T
    if fixed is None:
        x1 = x + np.dot(gain, y)
        p1 = p - np.dot(gain, pht.T)
        return x1, kernels.symmetrised(p1)
    kv = gain[:fixed]  # the Joseph form with K = [K_v; 0]: P - K H P - P H' K' + K S K'
    x1 = x.copy()
    x1[:fixed] += np.dot(kv, y)
    khp = np.dot(kv, pht.T)  # K_v H P, (fixed, n)
    p1 = p.copy()
    p1[:fixed] -= khp
    p1[:, :fixed] -= khp.T
    p1[:fixed, :fixed] += np.dot(np.dot(kv, s), kv.T)
    return x1, kernels.symmetrised(p1)


def add_landmarks(
    x: FloatArray,
    p: FloatArray,
    points: FloatArray,
    cov: FloatArray,
    offset: tuple[float, float],
) -> tuple[FloatArray, FloatArray]:
    """x and P with a landmark appended for each detection (module docstring).

    Args:
        x: the state, (n, 1).
        p: its covariance, (n, n).
        points: the detections in the sensor frame, (k, 2) [m].
        cov: their covariances there, (k, 2, 2) [m^2].
        offset: the sensor's planar origin in the antenna frame [m].

    Returns:
        (x (n + 2k, 1), P (n + 2k, n + 2k)), new arrays.
    """
    k = len(points)
    yaw = x.item(YAW)
    c, s = math.cos(yaw), math.sin(yaw)
    rot = np.array([[c, -s], [s, c]])
    rel = (points + np.asarray(offset)) @ rot.T  # m - p, (k, 2)
    m = rel + np.array([x.item(X), x.item(Y)])
    g3 = np.zeros((k, 2, 3))
    g3[:, 0, 0] = g3[:, 1, 1] = 1.0
    g3[:, 0, 2], g3[:, 1, 2] = -rel[:, 1], rel[:, 0]
    gx = g3.reshape(2 * k, 3)
    pose = [X, Y, YAW]
    cross = np.dot(gx, p[pose])  # P_mx, (2k, n)
    block = np.dot(cross[:, pose], gx.T)
    rz = np.einsum("ij,qjk,lk->qil", rot, cov, rot)
    idx = np.arange(k)
    block.reshape(k, 2, k, 2)[idx, :, idx, :] += rz
    n = len(x)
    x1 = np.vstack([x, m.reshape(-1, 1)])
    p1 = np.empty((n + 2 * k, n + 2 * k))
    p1[:n, :n] = p
    p1[n:, :n] = cross
    p1[:n, n:] = cross.T
    p1[n:, n:] = block
    return x1, kernels.symmetrised(p1)


def remove_landmarks(
    x: FloatArray, p: FloatArray, base: int, drop: IntArray
) -> tuple[FloatArray, FloatArray]:
    """x and P without landmarks ``drop`` (indices; landmark j at ``base + 2 j``): marginalised."""
    keep = np.ones(len(x), dtype=bool)
    keep[base + 2 * drop] = keep[base + 2 * drop + 1] = False
    return x[keep], p[np.ix_(keep, keep)]
