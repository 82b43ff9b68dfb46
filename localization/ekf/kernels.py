"""Compiled kernels (numba) of the fusion EKF: the motion model, and P's symmetrisation.

:func:`motion_terms` is the motion model, derived in its docstring: x' =
f(x, u, dt), the entries of F, of the input Jacobian G and of Q's model terms
in one compiled pass over floats, written into arrays the caller owns
(:class:`~localization.ekf.model.MotionStep` is its one typed call). Compiled
because it runs for every IMU sample, every replayed one and every estimate
ahead, and in Python each of its few dozen float results would cost an
interpreter round trip and a numpy item store. The two matrix products of Q
(G Sigma G') stay with numpy in the caller: numpy's BLAS uses fused
multiply-adds, which a loop here would not reproduce bit for bit.
:func:`symmetrised` is the ``0.5 * (P + P')`` the filter applies after every
predict and update, in one call instead of three numpy operations;
:func:`downdated` the large symmetric update of the map's covariance in
EKF-SLAM (its docstring says why compiled).

Exact arithmetic: no ``fastmath``, so no reassociation or contraction into
fused multiply-adds; ``math.sin``/``cos``/``exp``/``pow`` call the C
library's functions, as Python's ``math`` does (``dt ** 3`` is written
``math.pow(dt, 3.0)``, Python's float power, not numba's repeated
multiplication). So the kernel gives, bit for bit, the numbers of the
readable numpy formulation it was checked against; the tests keep that
formulation (``tests/localization/ekf_reference.py``) and compare exactly.

Caching as ``planner.kernels`` (``cache=True``: machine code is written next
to this file, or under ``NUMBA_CACHE_DIR`` or the user's cache directory;
with no writable directory the kernel compiles in each process, with a
warning). A cold cache compiles for seconds; a warm one loads in a
fraction of that.
"""

from __future__ import annotations

import math
from typing import Any, Final

import numpy as np

from conesim.core.compiled import cached_njit

# Layout of ``motion_terms``'s ``params``.
GPS_TAU, HEADING_TAU, QA, QW, QB, QS, GPS_VAR, HEADING_VAR = range(8)
N_PARAMS: Final = 8


def _probe() -> None:
    """Nothing: what ``cached_njit`` asks numba to cache, from this file's directory."""


# Cached beside this file (or under NUMBA_CACHE_DIR); with no writable cache
# directory, compiled in every process (a cold compile: see the module docstring).
_compiled = cached_njit(_probe, "conesim.localization.ekf.kernels")


@_compiled
def motion_terms(x, u, dt, g, h, params, out, f, gu, qm):  # noqa: PLR0917
    """The motion model: x' into ``out``; F, G and Q's model terms into ``f``, ``gu``, ``qm``.

    The IMU is the input u = (w_m, a_x, a_y), held over the interval dt (the
    state's table: :mod:`localization.ekf.model`). With w = w_m - gyro_bias,
    R(a) the 2D rotation and S = [[0, -1], [1, 0]] (so dR(a)/da = R(a) S), the
    body velocity rotates with the car and is pushed by the specific force
    a = (a_x, a_y); in ``reference`` the velocity is V = R(yaw) v and
    dV/dt = R(yaw) a. The steps below are the code's sections, in order.

    1. x' = f(x, u, dt), integrated with yaw at the interval's midpoint for
       the acceleration (second order)::

           p'   = p + dt R(yaw) v + dt^2/2 R(yaw + w dt/2) a
           yaw' = yaw + w dt
           v'   = R(-w dt) v + dt R(-w dt/2) a
           gyro_bias', wheel_scale' = gyro_bias, wheel_scale       (random walks)
           gps_bias' = phi_g gps_bias,  heading_bias' = phi_h heading_bias
           phi = exp(-dt/tau)                                       (Gauss-Markov)

    2. F = df/dx (identity except)::

           dp'/dyaw         = dt R(yaw) S v + dt^2/2 R(yaw + w dt/2) S a
           dp'/dv           = dt R(yaw)
           dp'/dgyro_bias   = -dt^3/4 R(yaw + w dt/2) S a
           dyaw'/dgyro_bias = -dt
           dv'/dv           = R(-w dt)
           dv'/dgyro_bias   = dt R(-w dt) S v + dt^2/2 R(-w dt/2) S a
           dgps_bias'/dgps_bias = phi_g I,  dheading_bias'/dheading_bias = phi_h

    3. G = df/du (w_m enters as -gyro_bias, so dG/dw_m = -dF/dgyro_bias;
       rows below vy are zero)::

           dp'/dw_m   = dt^3/4 R(yaw + w dt/2) S a     dp'/da = dt^2/2 R(yaw + w dt/2)
           dyaw'/dw_m = dt
           dv'/dw_m   = -dv'/dgyro_bias                dv'/da = dt R(-w dt/2)

    4. Q's model terms. The process noise is Q = G (Sigma_u T / dt) G^T +
       Q_model (the caller adds the first term), where Sigma_u is the IMU's
       stated per-sample variance at its period T (a white density of
       sigma^2 T, so splitting an IMU interval at a measurement keeps the
       total), and Q_model adds white acceleration (density q_a:
       Q_pp = q_a dt^3/3 I, Q_pv = q_a dt^2/2 R(yaw), Q_vv = q_a dt I), white
       yaw rate (q_w dt), the bias random walks (K^2 dt) and the exact
       Gauss-Markov terms sigma^2 (1 - phi^2).

    Args:
        x: state, (n, 1).
        u: IMU input (w_m, a_x, a_y), (3,).
        dt: interval [s], > 0.
        g: index of gps_bias_e, or -1 without that state.
        h: index of heading_bias, or -1 without that state.
        params: (8,): gps_bias_tau [s], heading_bias_tau [s], q_a = accel density^2
            [m^2/s^3], q_w = yaw density^2 [rad^2/s], gyro walk^2 [rad^2/s^3],
            scale walk^2 [1/s], gps_bias_sigma^2 [m^2], heading_bias_sigma^2 [rad^2]
            (indices ``GPS_TAU`` ... ``HEADING_VAR``).
        out: (n, 1), receives x' (yaw unwrapped); entries the model leaves alone are copied.
        f: (n, n), identity where the model has no entry; the entries are overwritten.
        gu: (n, 3), zero below row vy; rows x..vy are overwritten.
        qm: (n, n), zero where no model term; the terms are overwritten.
    """
    n = x.shape[0]
    px, py, yaw = x[0, 0], x[1, 0], x[2, 0]
    vx, vy, bias = x[3, 0], x[4, 0], x[5, 0]
    w_m, ax, ay = u[0], u[1], u[2]
    w = w_m - bias
    half = 0.5 * dt * dt
    cube = math.pow(dt, 3.0)
    c, s = math.cos(yaw), math.sin(yaw)
    mid = yaw + 0.5 * w * dt
    cm, sm = math.cos(mid), math.sin(mid)
    turn = -w * dt
    c1, s1 = math.cos(turn), math.sin(turn)
    turn_half = -0.5 * w * dt
    c2, s2 = math.cos(turn_half), math.sin(turn_half)
    vex, vey = c * vx - s * vy, s * vx + c * vy
    aex, aey = cm * ax - sm * ay, sm * ax + cm * ay
    sv0, sv1 = c * -vy - s * vx, s * -vy + c * vx
    sa0, sa1 = cm * -ay - sm * ax, sm * -ay + cm * ax
    dv0 = dt * (c1 * -vy - s1 * vx) + half * (c2 * -ay - s2 * ax)
    dv1 = dt * (s1 * -vy + c1 * vx) + half * (s2 * -ay + c2 * ax)
    phi_g = math.exp(-dt / params[GPS_TAU]) if g >= 0 else 1.0
    phi_h = math.exp(-dt / params[HEADING_TAU]) if h >= 0 else 1.0

    # -- 1. x' = f(x, u, dt) --
    for i in range(n):
        out[i, 0] = x[i, 0]
    out[0, 0] = px + (dt * vex + half * aex)
    out[1, 0] = py + (dt * vey + half * aey)
    out[2, 0] = yaw + w * dt
    out[3, 0] = (c1 * vx - s1 * vy) + dt * (c2 * ax - s2 * ay)
    out[4, 0] = (s1 * vx + c1 * vy) + dt * (s2 * ax + c2 * ay)
    if g >= 0:
        out[g, 0] *= phi_g
        out[g + 1, 0] *= phi_g
    if h >= 0:
        out[h, 0] *= phi_h

    # -- 2. F = df/dx (identity elsewhere) --
    wdt = w * dt
    cw, sw = math.cos(wdt), math.sin(wdt)
    f[0, 2] = dt * sv0 + half * sa0
    f[1, 2] = dt * sv1 + half * sa1
    f[0, 3], f[0, 4], f[1, 3], f[1, 4] = dt * c, -dt * s, dt * s, dt * c
    f[0, 5] = -0.25 * cube * sa0
    f[1, 5] = -0.25 * cube * sa1
    f[2, 5] = -dt
    f[3, 3], f[3, 4], f[4, 3], f[4, 4] = cw, sw, -sw, cw
    f[3, 5], f[4, 5] = dv0, dv1
    if g >= 0:
        f[g, g] = phi_g
        f[g + 1, g + 1] = phi_g
    if h >= 0:
        f[h, h] = phi_h

    # -- 3. G = df/du, rows x..vy --
    hw = 0.5 * w * dt
    ch, sh = math.cos(hw), math.sin(hw)
    gu[0, 0] = 0.25 * cube * sa0
    gu[1, 0] = 0.25 * cube * sa1
    gu[0, 1], gu[0, 2], gu[1, 1], gu[1, 2] = half * cm, -half * sm, half * sm, half * cm
    gu[2, 0] = dt
    gu[3, 0], gu[4, 0] = -dv0, -dv1
    gu[3, 1], gu[3, 2], gu[4, 1], gu[4, 2] = dt * ch, dt * sh, -dt * sh, dt * ch

    # -- 4. Q's model terms --
    qa = params[QA]
    if qa > 0.0:
        pp = qa * cube / 3.0
        pv = qa * dt * dt / 2.0
        qm[0, 0] = pp
        qm[1, 1] = pp
        pvc = pv * c
        qm[0, 3] = pvc
        qm[1, 4] = pvc
        qm[3, 0] = pvc
        qm[4, 1] = pvc
        pvs = pv * s
        qm[1, 3] = pvs
        qm[3, 1] = pvs
        pvm = pv * -s
        qm[0, 4] = pvm
        qm[4, 0] = pvm
        qv = qa * dt
        qm[3, 3] = qv
        qm[4, 4] = qv
    qm[2, 2] = params[QW] * dt
    qm[5, 5] = params[QB] * dt
    qm[6, 6] = params[QS] * dt
    if g >= 0:
        qg = params[GPS_VAR] * (1.0 - phi_g * phi_g)
        qm[g, g] = qg
        qm[g + 1, g + 1] = qg
    if h >= 0:
        qm[h, h] = params[HEADING_VAR] * (1.0 - phi_h * phi_h)


@_compiled
def symmetrised(p):
    """``0.5 * (p + p.T)`` as a new array: the same two operations per element as numpy's."""
    n = p.shape[0]
    out = np.empty((n, n))
    for i in range(n):
        for j in range(n):
            out[i, j] = 0.5 * (p[i, j] + p[j, i])
    return out


MIRROR_TILE: Final = 32  # the tile of ``downdated``'s mirror: rows and columns in cache


@_compiled
def downdated(m, u, v):
    """``m - u v`` as a new array, for a symmetric ``m`` (n, n) and a symmetric ``u v``
    (u (n, k), v (k, n), both C-contiguous): the lower triangle computed, the upper its
    mirror, so the result is exactly symmetric (the same numbers as numpy's ``m - u @ v``
    re-symmetrised, to rounding: the sums run in another order).

    The map's covariance update of EKF-SLAM (``localization.ekf.augmented``), compiled
    because at a few hundred landmarks it is the one large product of the filter, and
    OpenBLAS runs a product that size on several threads, which on a loaded or a shared
    machine cost 5-15x the single-threaded time (measured); this loop is single-threaded,
    half the work of the full product, and needs no separate symmetrisation.

    Each entry is ``m[i, j]`` minus the terms ``u[i, q] v[q, j]`` one at a time in the
    order of q, so its bits do not depend on how the loops are arranged: eight terms
    are taken per pass over a row (one load and store of the row for eight products
    instead of one each, the loop bound by arithmetic rather than memory), and the
    mirror goes by tiles (a column-wise write over the whole matrix missed the cache
    on every entry). Measured 1.3-1.5x the one-term loop at 200-350 landmarks.
    """
    n, k = u.shape
    out = np.empty((n, n))
    for i in range(n):
        row = out[i]
        mi = m[i]
        ui = u[i]
        for j in range(i + 1):
            row[j] = mi[j]
        q = 0
        while q + 8 <= k:
            a0, a1, a2, a3 = ui[q], ui[q + 1], ui[q + 2], ui[q + 3]
            a4, a5, a6, a7 = ui[q + 4], ui[q + 5], ui[q + 6], ui[q + 7]
            v0, v1, v2, v3 = v[q], v[q + 1], v[q + 2], v[q + 3]
            v4, v5, v6, v7 = v[q + 4], v[q + 5], v[q + 6], v[q + 7]
            for j in range(i + 1):
                r = (((row[j] - a0 * v0[j]) - a1 * v1[j]) - a2 * v2[j]) - a3 * v3[j]
                row[j] = (((r - a4 * v4[j]) - a5 * v5[j]) - a6 * v6[j]) - a7 * v7[j]
            q += 8
        while q < k:
            a = ui[q]
            vq = v[q]
            for j in range(i + 1):
                row[j] -= a * vq[j]
            q += 1
    tile = MIRROR_TILE
    for i0 in range(0, n, tile):
        i1 = min(i0 + tile, n)
        for j0 in range(0, i1, tile):
            for i in range(i0, i1):
                for j in range(j0, min(j0 + tile, i)):
                    out[j, i] = out[i, j]
    return out


def warm_up(step: Any, u: Any, u_cov: Any) -> None:
    """Call each kernel once, as the filter will (read-only state and input).

    numba initialises itself and loads (or compiles) the machine code on a
    kernel's first call, which is slow in a process that has used no numba
    yet. Called when a filter is built, so that this happens there rather
    than in its first predict (inside a timed loop, say). ``step`` is a
    ``MotionStep`` (its arrays are overwritten by every call, so the call
    leaves nothing behind); ``u`` and ``u_cov`` a read-only input and its
    covariance.
    """
    n = step.model.layout.n
    x = np.zeros((n, 1))
    x.flags.writeable = False
    step(x, u, u_cov, 0.01)
    symmetrised(np.eye(n))
    downdated(np.eye(2), np.zeros((2, 1)), np.zeros((1, 2)))
