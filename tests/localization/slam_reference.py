"""The dense Kalman steps of a state with landmarks: what ``localization.ekf.augmented`` computes.

The filter holds the map's part of the state in a compressed form
(``augmented.MapState``); these are the plain formulas on the whole (n, n)
P that it replaced (the filter's steps up to commit 5e3939e), kept so the
tests compare each compressed step, and a sequence of them, with them.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from conesim.localization.ekf.model import YAW, X, Y

FloatArray = NDArray[np.float64]


def predict(
    x: FloatArray, p: FloatArray, xv_next: FloatArray, f: FloatArray, q: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """x' = [f(x_v); x_m], P' = F P F' + Q with F = blockdiag(F_v, I), Q = blockdiag(Q_v, 0)."""
    n, nv = len(x), len(xv_next)
    big_f = np.eye(n)
    big_f[:nv, :nv] = f
    big_q = np.zeros((n, n))
    big_q[:nv, :nv] = q
    return np.vstack([xv_next, x[nv:]]), big_f @ p @ big_f.T + big_q


def update(
    x: FloatArray,
    p: FloatArray,
    y: FloatArray,
    h: FloatArray,
    r: FloatArray,
    *,
    fixed: int | None = None,
) -> tuple[FloatArray, FloatArray]:
    """The Joseph form with H (m, n) over the whole state; from ``fixed`` on the gain is
    zero (the Schmidt update of a frozen map)."""
    k = p @ h.T @ np.linalg.inv(h @ p @ h.T + r)
    if fixed is not None:
        k[fixed:] = 0.0
    ikh = np.eye(len(x)) - k @ h
    return x + k @ y, ikh @ p @ ikh.T + k @ r @ k.T


def add_landmarks(
    x: FloatArray,
    p: FloatArray,
    points: FloatArray,
    cov: FloatArray,
    offset: tuple[float, float],
) -> tuple[FloatArray, FloatArray]:
    """x and P with a landmark m = p + R(yaw) (z + o) appended per detection: P_mm =
    G_x P_pp G_x' + R R_z R', P_mx = G_x P_p (``augmented``'s module docstring)."""
    yaw = x.item(YAW)
    c, s = math.cos(yaw), math.sin(yaw)
    rot = np.array([[c, -s], [s, c]])
    n, k = len(x), len(points)
    rel = (points + np.asarray(offset)) @ rot.T
    gx = np.zeros((2 * k, n))
    for i in range(k):
        gx[2 * i : 2 * i + 2, [X, Y]] = np.eye(2)
        gx[2 * i, YAW], gx[2 * i + 1, YAW] = -rel[i, 1], rel[i, 0]
    rz = np.zeros((2 * k, 2 * k))
    for i in range(k):
        rz[2 * i : 2 * i + 2, 2 * i : 2 * i + 2] = rot @ cov[i] @ rot.T
    m = rel + np.array([x.item(X), x.item(Y)])
    big = np.vstack([np.eye(n), gx])
    p1 = big @ p @ big.T
    p1[n:, n:] += rz
    return np.vstack([x, m.reshape(-1, 1)]), p1


def remove_landmarks(
    x: FloatArray, p: FloatArray, base: int, drop: list[int]
) -> tuple[FloatArray, FloatArray]:
    """x and P without the landmarks ``drop`` (landmark j at ``base + 2 j``)."""
    gone = {base + 2 * j + a for j in drop for a in (0, 1)}
    keep = [i for i in range(len(x)) if i not in gone]
    return x[keep], p[np.ix_(keep, keep)]
