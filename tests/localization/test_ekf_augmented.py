"""The map's compressed Kalman steps against the dense formulas (``slam_reference``), to 1e-9."""

from __future__ import annotations

import math

import numpy as np
from filterpy.kalman import ExtendedKalmanFilter
from numpy.testing import assert_allclose

from conesim.localization.ekf import augmented, kernels
from conesim.localization.ekf.augmented import MapState
from tests.localization import slam_reference as ref

NV = 7  # vehicle states
L = 3  # landmarks
TOL = 1e-9


def _state(rng: np.random.Generator, landmarks: int = L) -> tuple[np.ndarray, np.ndarray]:
    n = NV + 2 * landmarks
    a = rng.normal(size=(n, n))
    return rng.normal(size=(n, 1)), a @ a.T / n + 0.1 * np.eye(n)


def _split(x: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray, MapState]:
    """(x_v, P_vv, the map's part) of a dense state, as the filter holds it."""
    ms = MapState(x[NV:].copy(), p[NV:, :NV].copy(), None, p[NV:, NV:].copy(), None)
    return x[:NV].copy(), p[:NV, :NV].copy(), ms


def _assert_dense(xv: np.ndarray, pvv: np.ndarray, ms: MapState, x: np.ndarray, p: np.ndarray):
    x1, p1 = augmented.dense(xv, pvv, ms)
    assert_allclose(x1, x, rtol=0, atol=TOL)
    assert_allclose(p1, p, rtol=0, atol=TOL)


def _predict(rng: np.random.Generator, xv: np.ndarray, pvv: np.ndarray, ms: MapState):
    """A random motion step: filterpy's P F' ... on the vehicle, the map's part after it,
    and the same step's (f(x_v), F, Q)."""
    f = np.eye(NV) + 0.1 * rng.normal(size=(NV, NV))
    q = 0.01 * np.eye(NV)
    xv1 = rng.normal(size=(NV, 1))
    return xv1, f @ pvv @ f.T + q, augmented.predicted(ms, f), (xv1, f, q)


def _vehicle_update(
    xv: np.ndarray, pvv: np.ndarray, ms: MapState, h: np.ndarray, y: np.ndarray, *, frozen: bool
):
    """filterpy's update of the vehicle with residual ``y``, then the map's part from its gain."""
    ekf = ExtendedKalmanFilter(dim_x=NV, dim_z=len(y))
    ekf.x, ekf.P = xv, pvv
    r = np.diag(np.full(len(y), 0.04))
    ekf.update(y, lambda _x: h, lambda _x: np.zeros_like(y), R=r)
    return ekf.x, ekf.P, augmented.measured(ms, h, ekf.K, ekf.SI, y, frozen=frozen), r


def test_predict_then_a_fix_is_the_dense_joseph_form() -> None:
    """Predict (F = blockdiag(F_v, I)), then a fix of x, y (H over the vehicle): the
    compressed state's dense x and P are the Joseph form's on the whole state, to 1e-9;
    twice, so T and C are products of steps."""
    rng = np.random.default_rng(1)
    x, p = _state(rng)
    xv, pvv, ms = _split(x, p)
    h = np.zeros((2, NV))
    h[0, 0] = h[1, 1] = 1.0
    for _ in range(2):
        xv, pvv, ms, step = _predict(rng, xv, pvv, ms)
        x, p = ref.predict(x, p, *step)
        _assert_dense(xv, pvv, ms, x, p)
        y = rng.normal(size=(2, 1))
        xv, pvv, ms, r = _vehicle_update(xv, pvv, ms, h, y, frozen=False)
        x, p = ref.update(x, p, y, np.hstack([h, np.zeros((2, 2 * L))]), r)
        _assert_dense(xv, pvv, ms, x, p)
    assert ms.t is not None and ms.c is not None  # held compressed


def test_frozen_map_takes_the_schmidt_update() -> None:
    """With the map frozen a heading update leaves the landmarks' means and P_mm as they
    were; the rest is the Joseph form with their gain zeroed, to 1e-9."""
    rng = np.random.default_rng(2)
    x, p = _state(rng)
    xv, pvv, ms = _split(x, p)
    h = np.zeros((1, NV))
    h[0, 2] = 1.0
    y = np.array([[0.05]])
    xv, pvv, ms1, r = _vehicle_update(xv, pvv, ms, h, y, frozen=True)
    x1, p1 = ref.update(x, p, y, np.hstack([h, np.zeros((1, 2 * L))]), r, fixed=NV)
    _assert_dense(xv, pvv, ms1, x1, p1)
    assert ms1.x is ms.x and ms1.m is ms.m and ms1.c is None


def _scan(rng: np.random.Generator, landmarks: list[int]) -> tuple[np.ndarray, np.ndarray]:
    """A random H over the pose (x, y, yaw) and each of ``landmarks``' (east, north), in the
    compact layout of ``scan_terms`` (m, NV + 2a) and on the whole state (m, n)."""
    a = len(landmarks)
    h = np.zeros((2 * a, NV + 2 * a))
    h[:, :3] = rng.normal(size=(2 * a, 3))
    h[:, NV:] = np.kron(np.eye(a), rng.normal(size=(2, 2)))
    big = np.zeros((2 * a, NV + 2 * L))
    big[:, :NV] = h[:, :NV]
    big[:, NV + augmented.entries(np.array(landmarks))] = h[:, NV:]
    return h, big


def test_scan_update_is_the_dense_update_while_building_and_frozen() -> None:
    """A scan of landmarks 2 and 0 after a predict and a fix (T and C held): S is H P H' + R
    and the state after it the dense Joseph form's, built (all gains) or frozen (the
    landmarks' gain zero), to 1e-9."""
    for frozen in (False, True):
        rng = np.random.default_rng(3)
        x, p = _state(rng)
        xv, pvv, ms = _split(x, p)
        xv, pvv, ms, step = _predict(rng, xv, pvv, ms)
        x, p = ref.predict(x, p, *step)
        hv = np.zeros((2, NV))
        hv[0, 0] = hv[1, 1] = 1.0
        y = rng.normal(size=(2, 1))
        xv, pvv, ms, r = _vehicle_update(xv, pvv, ms, hv, y, frozen=frozen)
        x, p = ref.update(x, p, y, np.hstack([hv, np.zeros((2, 2 * L))]), r, fixed=None)
        if frozen:  # the same prior as the building case's, frozen from here on
            xv, pvv, ms = _split(x, p)
        h, big = _scan(rng, [2, 0])
        r = 0.01 * np.eye(4)
        terms = augmented.scan_terms(pvv, ms, h, augmented.entries(np.array([2, 0])), r)
        assert_allclose(terms.s, big @ p @ big.T + r, rtol=0, atol=TOL)
        y = rng.normal(size=(4, 1))
        xv, pvv, ms1 = augmented.scan_update(xv, pvv, ms, y, terms, frozen=frozen)
        x, p = ref.update(x, p, y, big, r, fixed=NV if frozen else None)
        _assert_dense(xv, pvv, ms1, x, p)
        assert ms1.t is None and ms1.c is None  # written out
        if frozen:
            assert ms1.x is ms.x and ms1.m is ms.m


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
    ms = augmented.add_landmarks(x, p, MapState.empty(n), z, rz, offset=(0.0, 0.0))
    x1, p1 = augmented.dense(x, p, ms)

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
    """Dropping landmark 1 of 3 (with T and C held) leaves the other rows and columns of
    the dense P as they were."""
    rng = np.random.default_rng(4)
    x, p = _state(rng)
    xv, pvv, ms = _split(x, p)
    xv, pvv, ms, step = _predict(rng, xv, pvv, ms)
    x, p = ref.predict(x, p, *step)
    ms1 = augmented.remove_landmarks(ms, np.array([1]))
    _assert_dense(xv, pvv, ms1, *ref.remove_landmarks(x, p, NV, [1]))


def test_a_drive_of_mixed_steps_matches_the_dense_filter() -> None:
    """40 random steps (predicts, fixes, scans, landmarks added and one removed, the map frozen
    half way) on the compressed state and on the dense one: the same x and P to 1e-9."""
    rng = np.random.default_rng(5)
    x, p = _state(rng)
    p *= 0.01
    xv, pvv, ms = _split(x, p)
    h_fix = np.zeros((2, NV))
    h_fix[0, 0] = h_fix[1, 1] = 1.0
    for i in range(40):
        frozen = i >= 20
        kind = i % 5
        size = len(ms.x) // 2
        if kind in (0, 2):
            xv, pvv, ms, step = _predict(rng, xv, pvv, ms)
            x, p = ref.predict(x, p, *step)
        elif kind == 1:
            y = 0.1 * rng.normal(size=(2, 1))
            xv, pvv, ms, r = _vehicle_update(xv, pvv, ms, h_fix, y, frozen=frozen)
            big = np.hstack([h_fix, np.zeros((2, 2 * size))])
            x, p = ref.update(x, p, y, big, r, fixed=NV if frozen else None)
        elif kind == 3 and size >= 2:
            seen = [size - 1, 0]
            h = np.zeros((4, NV + 4))
            h[:, :3] = rng.normal(size=(4, 3))
            h[:, NV:] = np.kron(np.eye(2), rng.normal(size=(2, 2)))
            big = np.zeros((4, NV + 2 * size))
            big[:, :NV] = h[:, :NV]
            big[:, NV + augmented.entries(np.array(seen))] = h[:, NV:]
            r = 0.01 * np.eye(4)
            y = 0.1 * rng.normal(size=(4, 1))
            terms = augmented.scan_terms(pvv, ms, h, augmented.entries(np.array(seen)), r)
            xv, pvv, ms = augmented.scan_update(xv, pvv, ms, y, terms, frozen=frozen)
            x, p = ref.update(x, p, y, big, r, fixed=NV if frozen else None)
        elif kind == 4 and not frozen:
            z = rng.normal(size=(2, 2)) + np.array([5.0, 0.0])
            rz = np.tile(0.01 * np.eye(2), (2, 1, 1))
            ms = augmented.add_landmarks(xv, pvv, ms, z, rz, offset=(0.5, 0.1))
            x, p = ref.add_landmarks(x, p, z, rz, (0.5, 0.1))
            if i == 9:
                ms = augmented.remove_landmarks(ms, np.array([1]))
                x, p = ref.remove_landmarks(x, p, NV, [1])
        _assert_dense(xv, pvv, ms, x, p)
    assert len(ms.x) == 2 * (L + 2 * 4 - 1)  # 4 scans added 2 each, 1 removed


def test_downdated_is_m_minus_u_v_exactly_symmetric() -> None:
    """Worked: [[4, 1], [1, 3]] - [1; 2] [1, 2] = [[3, -1], [-1, -1]]; and on a 50 x 50
    random case numpy's m - u v to 1e-12, with the result exactly symmetric."""
    out = kernels.downdated(np.array([[4.0, 1.0], [1.0, 3.0]]), np.array([[1.0], [2.0]]),
                            np.array([[1.0, 2.0]]))  # fmt: skip
    assert_allclose(out, [[3.0, -1.0], [-1.0, -1.0]], rtol=0, atol=0)
    rng = np.random.default_rng(6)
    m, u, w = rng.normal(size=(50, 50)), rng.normal(size=(50, 6)), rng.normal(size=(6, 6))
    m, w = m + m.T, w + w.T
    v = w @ u.T
    out = kernels.downdated(m, u, v)
    assert np.array_equal(out, out.T)
    assert_allclose(out, m - u @ v, rtol=0, atol=1e-12)


def _downdated_term_by_term(m: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``kernels.downdated``'s arithmetic written plainly: each lower entry is m[i, j] minus
    u[i, q] v[q, j] one term at a time in the order of q, the upper entry its mirror."""
    n, k = u.shape
    out = np.empty((n, n))
    for i in range(n):
        for j in range(i + 1):
            r = m[i, j]
            for q in range(k):
                r -= u[i, q] * v[q, j]
            out[i, j] = out[j, i] = r
    return out


def test_downdated_takes_the_terms_in_order_eight_at_a_time_bit_for_bit() -> None:
    """The kernel's eight-term passes and its tiled mirror give the bits of the plain
    term-by-term loop (the numbers the filter had before), for k below, at and past
    multiples of 8, and n past the mirror's 32-row tiles and not a multiple of them."""
    rng = np.random.default_rng(16)
    for n, k in ((70, 8), (70, 13), (45, 28), (33, 3)):
        m, u, w = rng.normal(size=(n, n)), rng.normal(size=(n, k)), rng.normal(size=(k, k))
        m, w = m + m.T, w + w.T
        v = np.ascontiguousarray(w @ u.T)
        out = kernels.downdated(m, np.ascontiguousarray(u), v)
        assert np.array_equal(out, _downdated_term_by_term(m, u, v)), (n, k)
        assert np.array_equal(out, out.T)
