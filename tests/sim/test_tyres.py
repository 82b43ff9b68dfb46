"""Tests of the tyre formulas against their closed forms and fssim's convention."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st
from numpy.testing import assert_allclose
from scipy.optimize import minimize_scalar

from conesim.sim.tyres import PacejkaParams, friction_ellipse, lateral_force, slip_angles

TYRE = PacejkaParams()
FZ = 931.95  # [N] one axle of the default car: 190 kg * 9.81 / 2


def test_zero_slip_gives_zero_force() -> None:
    """No slip, no lateral force."""
    assert lateral_force(0.0, FZ, TYRE) == 0.0


def test_positive_slip_gives_leftward_force_and_curve_is_odd() -> None:
    """Sign convention: alpha > 0 pushes left; Fy(-alpha) = -Fy(alpha)."""
    for alpha in (0.01, 0.1, 0.3, 1.0):
        fy = lateral_force(alpha, FZ, TYRE)
        assert fy > 0.0
        assert lateral_force(-alpha, FZ, TYRE) == -fy


def test_slope_at_zero_is_bcd_times_load() -> None:
    """C_alpha = B*C*D*mu*Fz = 12.56*1.38*1.60*931.95 = 25,846 N/rad."""
    h = 1e-7
    slope = (lateral_force(h, FZ, TYRE) - lateral_force(-h, FZ, TYRE)) / (2 * h)
    print(f"cornering stiffness: sim {slope:.1f} N/rad, theory {TYRE.stiffness_per_load * FZ:.1f}")
    assert_allclose(slope, 12.56 * 1.38 * 1.60 * FZ, rtol=1e-6)


def test_peak_is_mu_d_fz() -> None:
    """The curve peaks at mu*D*Fz = 0.8*1.6*931.95 = 1192.9 N near alpha = 0.140 rad."""
    mu = 0.8
    res = minimize_scalar(
        lambda a: -lateral_force(a, FZ, TYRE, mu),
        bounds=(0.0, 0.5),
        method="bounded",
        options={"xatol": 1e-10},
    )
    print(f"Pacejka peak: {-res.fun:.2f} N at {res.x:.4f} rad; mu*D*Fz = {mu * 1.6 * FZ:.2f} N")
    assert_allclose(-res.fun, mu * 1.6 * FZ, rtol=1e-9)
    assert_allclose(res.x, 0.140, atol=5e-4)


def test_mu_scales_the_whole_curve() -> None:
    """Half the surface friction halves the force at any slip."""
    for alpha in (0.02, 0.14, 0.5):
        assert_allclose(
            lateral_force(alpha, FZ, TYRE, 0.5), 0.5 * lateral_force(alpha, FZ, TYRE), rtol=1e-12
        )


def test_matches_fssim_formula_with_its_sign_convention() -> None:
    """fssim: Fy = Fz D sin(C atan(B(1-E)a + E atan(B a))), C = -1.38, a = -alpha."""
    b, c, d, e = 12.56, -1.38, 1.60, -0.58
    for alpha in (-0.4, -0.05, 0.003, 0.14, 0.9):
        a = -alpha
        fssim = FZ * d * math.sin(c * math.atan(b * (1 - e) * a + e * math.atan(b * a)))
        assert_allclose(lateral_force(alpha, FZ, TYRE), fssim, rtol=1e-12)


def test_negative_c_is_rejected_with_the_field_named() -> None:
    """fssim's negative C must be given as |C| here."""
    with pytest.raises(ValueError, match=r"PacejkaParams\.C must be in \(0, 2\)"):
        PacejkaParams(C=-1.38)
    with pytest.raises(ValueError, match=r"PacejkaParams\.E"):
        PacejkaParams(E=1.5)


def test_slip_angles_match_textbook_for_forward_motion() -> None:
    """alpha_f = delta - atan((vy + lf r)/vx), alpha_r = -atan((vy - lr r)/vx)."""
    vx, vy, r, delta, lf, lr = 10.0, 0.3, 0.4, 0.1, 0.765, 0.765
    af, ar = slip_angles(vx, vy, r, delta, lf=lf, lr=lr)
    assert_allclose(af, delta - math.atan((vy + lf * r) / vx), rtol=1e-12)
    assert_allclose(ar, -math.atan((vy - lr * r) / vx), rtol=1e-12)


def test_slip_angles_when_rolling_backwards_or_sliding_sideways() -> None:
    """Straight backwards: no slip; sliding left: the force points right."""
    assert slip_angles(-3.0, 0.0, 0.0, 0.0, lf=0.8, lr=0.7) == (0.0, 0.0)
    af, ar = slip_angles(0.0, 2.0, 0.0, 0.0, lf=0.8, lr=0.7)
    assert af < -1.5
    assert ar < -1.5


def test_friction_ellipse_keeps_pure_slip_forces() -> None:
    """No longitudinal force: the lateral force is untouched."""
    assert friction_ellipse(0.0, 800.0, FZ, 1.6) == (0.0, 800.0)


@given(
    fx=st.floats(-5000.0, 5000.0),
    fy_ratio=st.floats(-1.0, 1.0),
    fz=st.floats(0.0, 3000.0),
    mu=st.floats(0.1, 2.0),
)
def test_friction_ellipse_bounds_the_combined_force(
    fx: float, fy_ratio: float, fz: float, mu: float
) -> None:
    """(Fx/(mu Fz))^2 + (Fy/(mu Fz))^2 <= 1, signs kept, |Fy| never grows."""
    fy0 = fy_ratio * mu * fz
    out_x, out_y = friction_ellipse(fx, fy0, fz, mu)
    f_max = mu * fz
    assert out_x**2 + out_y**2 <= f_max**2 * (1 + 1e-12) + 1e-18
    assert abs(out_y) <= abs(fy0)
    assert out_x * fx >= 0.0
    assert out_y * fy0 >= 0.0
