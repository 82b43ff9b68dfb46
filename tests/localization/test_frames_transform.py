"""Tests for localization.frames.transform and .rigid: the transform type and its maths."""

from __future__ import annotations

import math

import numpy as np
import scipy
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose
from scipy.spatial.transform import Rotation, Slerp

from conesim.core.pose import Pose2D
from conesim.localization.frames import TransformStamped, rigid

IDENTITY_MATRIX = np.eye(4)


def random_transform(rng: np.random.Generator, parent: str, child: str) -> TransformStamped:
    """A transform with a uniformly random rotation and a translation within 10 m."""
    q = Rotation.random(random_state=rng).as_quat()
    return TransformStamped(parent, child, 0.0, rng.uniform(-10.0, 10.0, 3), q)


def same_rotation(q: np.ndarray, r: np.ndarray) -> bool:
    """Whether two unit quaternions give one rotation (q and -q do)."""
    return bool(abs(abs(np.dot(q, r)) - 1.0) < 1e-12)


def test_from_pose2d_places_child_and_round_trips() -> None:
    """from_pose2d sets x, y, z and a yaw-only quaternion; to_pose2d gives the pose back."""
    t = TransformStamped.from_pose2d("reference", "gps_antenna", 2.5, Pose2D(1.5, -2.0, 2.0), 0.3)
    assert_allclose(t.translation, [1.5, -2.0, 0.3], atol=1e-12)
    assert_allclose(t.rotation, [0.0, 0.0, math.sin(1.0), math.cos(1.0)], atol=1e-12)
    pose = t.to_pose2d()
    assert_allclose([pose.x, pose.y, pose.yaw], [1.5, -2.0, 2.0], atol=1e-12)
    assert t.stamp == 2.5


def test_to_pose2d_yaw_matches_scipy_zyx() -> None:
    """to_pose2d's yaw is scipy's first Z-Y-X Euler angle, wrapped into [-pi, pi)."""
    rng = np.random.default_rng(0)
    for _ in range(100):
        t = random_transform(rng, "a", "b")
        expected = Rotation.from_quat(t.rotation).as_euler("ZYX")[0]
        assert_allclose(t.to_pose2d().yaw, expected, atol=1e-9)
        assert -math.pi <= t.to_pose2d().yaw < math.pi


def test_quaternion_within_tolerance_is_stored_normalised() -> None:
    """A quaternion off unit norm by less than the tolerance is accepted and normalised."""
    q = np.array([0.0, 0.0, math.sin(0.3), math.cos(0.3)]) * (1.0 + 5e-7)
    t = TransformStamped("a", "b", 0.0, (0.0, 0.0, 0.0), q)
    assert_allclose(np.linalg.norm(t.rotation), 1.0, atol=1e-15)


def test_arrays_are_read_only_copies() -> None:
    """The stored arrays are copies that cannot be written."""
    translation = np.array([1.0, 2.0, 3.0])
    t = TransformStamped("a", "b", 0.0, translation)
    translation[0] = 99.0
    assert t.translation[0] == 1.0
    assert not t.translation.flags.writeable
    assert not t.rotation.flags.writeable


def test_as_matrix_matches_scipy() -> None:
    """as_matrix holds scipy's rotation matrix and the translation."""
    rng = np.random.default_rng(0)
    t = random_transform(rng, "a", "b")
    m = t.as_matrix()
    assert_allclose(m[:3, :3], Rotation.from_quat(t.rotation).as_matrix(), atol=1e-12)
    assert_allclose(m[:3, 3], t.translation, atol=0.0)
    assert_allclose(m[3], [0.0, 0.0, 0.0, 1.0], atol=0.0)


def test_compose_matches_matrix_product_and_scipy() -> None:
    """a.compose(b) is the product of the homogeneous matrices and of scipy rotations."""
    rng = np.random.default_rng(0)
    for _ in range(50):
        a = random_transform(rng, "A", "B")
        b = random_transform(rng, "B", "C")
        ab = a.compose(b)
        assert (ab.frame_id, ab.child_frame_id) == ("A", "C")
        assert_allclose(ab.as_matrix(), a.as_matrix() @ b.as_matrix(), atol=1e-9)
        expected = Rotation.from_quat(a.rotation) * Rotation.from_quat(b.rotation)
        assert same_rotation(ab.rotation, expected.as_quat())


def test_inverse_composed_is_identity() -> None:
    """t ∘ t⁻¹ and t⁻¹ ∘ t are the identity to 1e-9, and inverse swaps the frames."""
    rng = np.random.default_rng(0)
    for _ in range(50):
        t = random_transform(rng, "A", "B")
        inv = t.inverse()
        assert (inv.frame_id, inv.child_frame_id, inv.stamp) == ("B", "A", t.stamp)
        assert_allclose(t.compose(inv).as_matrix(), IDENTITY_MATRIX, atol=1e-9)
        assert_allclose(inv.compose(t).as_matrix(), IDENTITY_MATRIX, atol=1e-9)
        assert_allclose(inv.as_matrix(), np.linalg.inv(t.as_matrix()), atol=1e-9)


def test_transform_points_3d_and_2d() -> None:
    """(n, 3) points map as R p + t; (n, 2) points map as z = 0 with z dropped."""
    rng = np.random.default_rng(0)
    t = random_transform(rng, "A", "B")
    points = rng.uniform(-5.0, 5.0, (7, 3))
    expected = Rotation.from_quat(t.rotation).apply(points) + t.translation
    assert_allclose(t.transform_points(points), expected, atol=1e-9)
    flat = points.copy()
    flat[:, 2] = 0.0
    assert_allclose(t.transform_points(points[:, :2]), t.transform_points(flat)[:, :2], atol=1e-12)
    assert t.transform_points(np.empty((0, 2))).shape == (0, 2)


def test_rigid_invert_matches_scipy() -> None:
    """rigid.invert is scipy's inverse rotation with t' = -R⁻¹ t."""
    rng = np.random.default_rng(0)
    t = random_transform(rng, "A", "B")
    inv = rigid.invert(t.rigid)
    r_inv = Rotation.from_quat(t.rotation).inv()
    assert same_rotation(np.array(inv[3:]), r_inv.as_quat())
    # A writeable copy: scipy 1.17.1's Rotation.apply rejects read-only arrays (scipy#24751).
    assert_allclose(inv[:3], -r_inv.apply(np.array(t.translation)), atol=1e-12)


def test_interpolate_matches_scipy_slerp() -> None:
    """rigid.interpolate equals scipy Slerp for the rotation and a lerp for the translation."""
    rng = np.random.default_rng(0)
    for _ in range(50):
        a = random_transform(rng, "A", "B").rigid
        b = random_transform(rng, "A", "B").rigid
        step = rigid.slerp_step(a, b)
        slerp = Slerp([0.0, 1.0], Rotation.from_quat([a[3:], b[3:]]))
        for ratio in (0.0, 0.25, 0.5, 0.9, 1.0):
            out = rigid.interpolate(a, b, step, ratio)
            expected_t = np.array(a[:3]) + ratio * (np.array(b[:3]) - np.array(a[:3]))
            assert_allclose(out[:3], expected_t, atol=1e-12)
            assert same_rotation(np.array(out[3:]), slerp([ratio]).as_quat()[0])


def _exactly(a: tuple[float, ...], b: tuple[float, ...]) -> bool:
    """The same floats, bit for bit (sign of zero included)."""
    return all(
        x == y and math.copysign(1.0, x) == math.copysign(1.0, y) for x, y in zip(a, b, strict=True)
    )


def test_rotvec_of_is_scipy_bit_for_bit() -> None:
    """rigid.rotvec_of gives scipy's from_quat(q).as_rotvec() exactly: general, planar (the
    broadcaster's yaw-only steps), tiny and near-pi angles, w < 0 and w == 0."""
    rng = np.random.default_rng(7)
    cases: list[tuple[float, ...]] = []
    for k in range(20_000):
        q = rng.normal(size=4) * 10.0 ** rng.uniform(-3.0, 3.0)
        if k % 4 == 1:
            q[:2] = 0.0
        elif k % 4 == 2:
            yaw = rng.normal() * 10.0 ** rng.uniform(-8.0, 0.5)
            q = np.array([0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2)])
        if k % 50 == 0:
            q[3] = 0.0
        if k % 70 == 0:
            q[0] = q[3] = 0.0
        if k % 3 == 0:
            q[3] = -abs(q[3])
        cases.append(tuple(float(v) for v in q))
    cases += [
        (0.0, 0.0, 0.0, 1.0),
        (0.0, 0.0, 0.0, -1.0),
        (0.0, 0.0, -1.0, 0.0),
        (-0.0, 0.0, 0.0, 1.0),
    ]
    # rotvec_of writes out scipy 1.17's as_rotvec step by step; another scipy
    # may round differently, so there the check is to a few ulp.
    same_scipy = scipy.__version__.startswith("1.17.")
    for q in cases:
        expected = tuple(float(v) for v in Rotation.from_quat(q).as_rotvec())
        got = rigid.rotvec_of(q)  # type: ignore[arg-type]
        if same_scipy:
            assert _exactly(got, expected), q
        else:
            np.testing.assert_allclose(got, expected, rtol=4 * np.finfo(float).eps, atol=1e-300)


def test_slerp_takes_the_shorter_way() -> None:
    """Half-way from yaw 0 to yaw 170 deg, given as -q, is yaw 85 deg (not -95 deg)."""
    a = TransformStamped.from_pose2d("A", "B", 0.0, Pose2D(0.0, 0.0, 0.0)).rigid
    b = TransformStamped("A", "B", 0.0, rotation=-Rotation.from_euler("z", 170, True).as_quat())
    mid = rigid.interpolate(a, b.rigid, rigid.slerp_step(a, b.rigid), 0.5)
    assert_allclose(rigid.yaw_of(mid), math.radians(85.0), atol=1e-12)


unit = st.floats(-1.0, 1.0, allow_nan=False)
coordinate = st.floats(-1e3, 1e3, allow_nan=False)
quaternions = st.tuples(unit, unit, unit, unit).filter(lambda q: np.linalg.norm(q) > 0.1)
transforms = st.builds(
    lambda t, q: TransformStamped("A", "B", 0.0, t, np.array(q) / np.linalg.norm(q)),
    st.tuples(coordinate, coordinate, coordinate),
    quaternions,
)


@settings(derandomize=True, database=None, deadline=None, max_examples=300)
@given(a=transforms, b=transforms)
def test_compose_and_inverse_properties(a: TransformStamped, b: TransformStamped) -> None:
    """For any transforms: a ∘ a⁻¹ = I, (a ∘ b)⁻¹ = b⁻¹ ∘ a⁻¹, and points round-trip."""
    b = TransformStamped("B", "C", 0.0, b.translation, b.rotation)
    assert_allclose(a.compose(a.inverse()).as_matrix(), IDENTITY_MATRIX, atol=1e-9)
    ab = a.compose(b)
    assert_allclose(
        ab.inverse().as_matrix(), b.inverse().compose(a.inverse()).as_matrix(), atol=1e-9
    )
    points = np.array([[1.0, -2.0, 0.5], [0.0, 0.0, 0.0], [30.0, 4.0, -7.0]])
    assert_allclose(ab.inverse().transform_points(ab.transform_points(points)), points, atol=1e-9)
