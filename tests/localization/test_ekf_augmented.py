"""The structured Kalman steps of a state with landmarks against the dense formulas."""

from __future__ import annotations

import math

import numpy as np
from numpy.testing import assert_allclose

from conesim.localization.ekf import augmented

NV = 7  # vehicle states
L = 3  # landmarks


def _state(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    n = NV + 2 * L
    a = rng.normal(size=(n, n))
    return rng.normal(size=(n, 1)), a @ a.T / n + 0.1 * np.eye(n)


def test_predict_is_the_dense_f_p_f_plus_q() -> None:
    """With F = blockdiag(F_v, I) and Q = blockdiag(Q_v, 0): the same x and P to 1e-12."""
    rng = np.random.default_rng(0)
    x, p = _state(rng)
    f = np.eye(NV) + 0.1 * rng.normal(size=(NV, NV))
    q = 0.01 * np.eye(NV)
    xv = rng.normal(size=(NV, 1))
    x1, p1 = augmented.predict(x, p, xv, f, q)
    big_f = np.eye(len(x))
    big_f[:NV, :NV] = f
    big_q = np.zeros_like(p)
    big_q[:NV, :NV] = q
    assert_allclose(x1, np.vstack([xv, x[NV:]]), atol=0)
    assert_allclose(p1, big_f @ p @ big_f.T + big_q, atol=1e-12)


def test_update_is_the_joseph_form() -> None:
    """A GPS-like measurement of x, y (H over the first 2 columns): the Joseph form's P
    and the gain's x, to 1e-12."""
    rng = np.random.default_rng(1)
    x, p = _state(rng)
    h = np.zeros((2, 2))
    h[0, 0] = h[1, 1] = 1.0
    r = np.diag([0.04, 0.09])
    y = np.array([[0.3], [-0.2]])
    x1, p1 = augmented.update(x, p, y, h, r)
    big_h = np.zeros((2, len(x)))
    big_h[:, :2] = h
    k = p @ big_h.T @ np.linalg.inv(big_h @ p @ big_h.T + r)
    ikh = np.eye(len(x)) - k @ big_h
    assert_allclose(x1, x + k @ y, atol=1e-12)
    assert_allclose(p1, ikh @ p @ ikh.T + k @ r @ k.T, atol=1e-12)


def test_schmidt_update_holds_the_landmarks() -> None:
    """``fixed=NV``: the landmarks' means and covariance stay; the rest is the Joseph form
    with their gain zeroed, to 1e-12."""
    rng = np.random.default_rng(2)
    x, p = _state(rng)
    big_h = rng.normal(size=(2, len(x)))
    r = np.diag([0.01, 0.01])
    y = np.array([[0.1], [0.05]])
    x1, p1 = augmented.update(x, p, y, big_h, r, fixed=NV)
    k = p @ big_h.T @ np.linalg.inv(big_h @ p @ big_h.T + r)
    k[NV:] = 0.0
    ikh = np.eye(len(x)) - k @ big_h
    assert_allclose(x1[NV:], x[NV:], atol=0)
    assert_allclose(p1[NV:, NV:], p[NV:, NV:], atol=1e-15)
    assert_allclose(x1, x + k @ y, atol=1e-12)
    assert_allclose(p1, ikh @ p @ ikh.T + k @ r @ k.T, atol=1e-12)


def test_new_landmark_takes_the_linearised_covariance() -> None:
    """A cone 5 m ahead and 2 m left, seen from yaw 30 deg: m = p + R z, and P_mm, P_mx
    are G_x P G_x' + R R_z R', G_x P, with G from finite differences of m(x, z)."""
    rng = np.random.default_rng(3)
    n = NV
    a = rng.normal(size=(n, n))
    p = 0.01 * (a @ a.T / n + np.eye(n))
    x = np.zeros((n, 1))
    x[:3, 0] = (1.0, 2.0, math.radians(30.0))
    z = np.array([[5.0, 2.0]])
    rz = np.array([[[0.0025, 0.0004], [0.0004, 0.0016]]])
    x1, p1 = augmented.add_landmarks(x, p, z, rz, (0.0, 0.0))

    def cone(xs: np.ndarray, zs: np.ndarray) -> np.ndarray:
        c, s = math.cos(xs[2, 0]), math.sin(xs[2, 0])
        return xs[:2, 0] + np.array([c * zs[0] - s * zs[1], s * zs[0] + c * zs[1]])

    c30, s30 = math.cos(math.radians(30.0)), math.sin(math.radians(30.0))
    assert_allclose(x1[n:, 0], [1.0 + 5.0 * c30 - 2.0 * s30, 2.0 + 5.0 * s30 + 2.0 * c30])
    gx = np.zeros((2, n))
    for i in range(3):
        step = np.zeros((n, 1))
        step[i] = 1e-6
        gx[:, i] = (cone(x + step, z[0]) - cone(x - step, z[0])) / 2e-6
    rot = np.array([[c30, -s30], [s30, c30]])
    assert_allclose(p1[n:, :n], gx @ p, atol=1e-9)
    assert_allclose(p1[n:, n:], gx @ p @ gx.T + rot @ rz[0] @ rot.T, atol=1e-9)


def test_removing_a_landmark_marginalises_it() -> None:
    """Dropping landmark 1 of 3 leaves the other rows and columns as they were."""
    rng = np.random.default_rng(4)
    x, p = _state(rng)
    x1, p1 = augmented.remove_landmarks(x, p, NV, np.array([1]))
    keep = [*range(NV), NV, NV + 1, NV + 4, NV + 5]
    assert_allclose(x1, x[keep], atol=0)
    assert_allclose(p1, p[np.ix_(keep, keep)], atol=0)
