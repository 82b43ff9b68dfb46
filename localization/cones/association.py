"""Which map cone each detection of a scan is: gated nearest neighbours, then a consensus.

1. **Candidates.** Each detection is predicted into ``reference`` with the
   prior pose, w_i = p + R(yaw) (z_i + o), and ``scipy.spatial.cKDTree``
   returns the map cones within a radius that bounds its gate (the trace of
   its innovation covariance, capped at ``max_search_radius``).
2. **Mahalanobis gate.** Each (detection, cone) pair's innovation
   nu = w_i - (m_j + b), with S = A P A' + R(yaw) R_i R(yaw)' where
   A = [-I, a, I] over (x, y, yaw, map_bias), a = (d_y, -d_x),
   d = m_j + b - p, is the sensor-frame innovation rotated into
   ``reference`` (the same d^2 = nu' S^-1 nu; b and its column only with a
   map offset in the state). Pairs beyond ``chi2.ppf(gate_probability, 2)``
   are out.
3. **Colours.** With ``use_colours``, a detection that reports a colour
   keeps only cones of its class (a big orange cone is orange; ``unknown``
   matches any).
4. **Unique or consensus.** When every detection has at most one candidate
   and no cone is claimed twice, those pairs are the association. Otherwise
   (dense cones, a large prior after initialisation) every candidate pair
   proposes the map offset delta = m_j - w_i; the offset that the most
   detections agree with (within ``consensus_tolerance`` plus the yaw
   sigma's share at their range), the most likely under the prior when
   tied, wins, and each detection takes its pair nearest to it, each cone
   claimed once (mutual exclusion). Fewer than ``min_consensus`` agreeing
   detections: nothing is associated. The filter then tests the chosen set's
   joint NIS (joint compatibility) before using it.

Why not JCBB (Neira and Tardos 2001): its branch and bound is exponential in
the detections, and a scan has 10-30; the consensus is one vectorised
O(pairs^2) step, and the joint test afterwards is JCBB's own criterion on the
set it picks. Hand-written because neither filterpy nor scipy associates
data; the k-d tree is scipy's.

Counts (``ConeCounts``): a detection with no cone in its gate is a false
positive; one whose gated cones all have another colour, a colour mismatch;
one left out by step 4, ambiguous; a map cone in range and field of view
that nothing matched, a miss.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from conesim.localization.cones.config import ConeUpdateConfig
from conesim.localization.cones.landmarks import LandmarkMap
from conesim.localization.ekf.health import ConeCounts
from conesim.localization.ekf.model import YAW, X, Y

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]
_NONE = np.zeros(0, dtype=np.intp)
_NONE.setflags(write=False)


@dataclass(frozen=True, slots=True)
class Association:
    """A scan's detections matched to map cones.

    Attributes:
        detections: indices of the matched detections, (a,).
        landmarks: the map cone of each, (a,).
        counts: the scan's counts (``scans`` = 1; ``matched`` = a).
        missed: the map cones in range and field of view that nothing matched, (misses,).
        unmatched: the detections with no map cone in their gate (the false
            positives; a map being built takes them as candidates), (false_positives,).
    """

    detections: IntArray
    landmarks: IntArray
    counts: ConeCounts
    missed: IntArray = field(default_factory=lambda: _NONE)
    unmatched: IntArray = field(default_factory=lambda: _NONE)

    def __len__(self) -> int:
        return len(self.detections)


class StateCones(NamedTuple):
    """The covariance of map cones that are states (SLAM, ``localization.slam``).

    Attributes:
        pose: each cone's covariance with (x, y, yaw), (L, 3, 2) [m^2, m rad].
        own: each cone's own, (L, 2, 2) [m^2].
    """

    pose: FloatArray
    own: FloatArray


def _rotation(yaw: float) -> FloatArray:
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s], [s, c]])


def _candidates(lmap: LandmarkMap, w: FloatArray, radius: FloatArray) -> tuple[IntArray, IntArray]:
    """(detection, cone) index pairs with the cone within ``radius`` of ``w``."""
    found = lmap.tree.query_ball_point(w, radius)
    sizes = np.fromiter((len(f) for f in found), dtype=np.intp, count=len(found))
    if not sizes.sum():
        return _NONE, _NONE
    det = np.repeat(np.arange(len(w), dtype=np.intp), sizes)
    cone = np.fromiter((j for f in found for j in f), dtype=np.intp, count=int(sizes.sum()))
    return det, cone


def _mahalanobis(
    pose: FloatArray, pk: FloatArray, w: FloatArray, rw: FloatArray, cones: FloatArray
) -> FloatArray:
    """d^2 of each pair: detection at ``w`` (q, 2) with world covariance ``rw``
    (q, 2, 2) against map cone ``cones`` (q, 2), offset included (module
    docstring, step 2); ``pk``: P over (x, y, yaw[, map_bias]), (3, 3) or (5, 5),
    or per pair over (x, y, yaw, cone), (q, 5, 5), when the cones are states (SLAM)."""
    d = cones - pose[:2]
    k = pk.shape[-1]
    a = np.zeros((len(cones), 2, k))
    a[:, 0, 0] = a[:, 1, 1] = -1.0
    a[:, 0, 2], a[:, 1, 2] = d[:, 1], -d[:, 0]
    if k == 5:
        a[:, 0, 3] = a[:, 1, 4] = 1.0
    spec = "qik,kl,qjl->qij" if pk.ndim == 2 else "qik,qkl,qjl->qij"
    s = np.einsum(spec, a, pk, a) + rw
    n0, n1 = w[:, 0] - cones[:, 0], w[:, 1] - cones[:, 1]
    s00, s01, s11 = s[:, 0, 0], s[:, 0, 1], s[:, 1, 1]
    det = s00 * s11 - s01 * s01
    return (n0 * n0 * s11 - 2.0 * n0 * n1 * s01 + n1 * n1 * s00) / det


def _consensus(
    det: IntArray,
    cone: IntArray,
    offset: FloatArray,
    *,
    tolerance: FloatArray,
    prior_inv: FloatArray,
    k: int,
) -> tuple[IntArray, IntArray]:
    """Step 4's consensus over candidate pairs: the pairs chosen (detection, cone)."""
    gap = np.linalg.norm(offset[:, None, :] - offset[None, :, :], axis=2)
    close = gap <= tolerance[None, :]
    onehot = np.zeros((len(det), k))
    onehot[np.arange(len(det)), det] = 1.0
    support = (close.astype(float) @ onehot > 0.0).sum(axis=1)
    best = support == support.max()
    likelihood = np.einsum("qi,ij,qj->q", offset, prior_inv, offset)
    h = int(np.flatnonzero(best)[np.argmin(likelihood[best])])
    agree = np.flatnonzero(close[h])
    order = agree[np.argsort(gap[h, agree], kind="stable")]
    seen_det: set[int] = set()
    seen_cone: set[int] = set()
    keep: list[int] = []
    for q in order.tolist():
        i, j = int(det[q]), int(cone[q])
        if i in seen_det or j in seen_cone:
            continue
        seen_det.add(i)
        seen_cone.add(j)
        keep.append(q)
    chosen = np.array(sorted(keep, key=lambda q: int(det[q])), dtype=np.intp)
    return det[chosen], cone[chosen]


def _missed(
    lmap: LandmarkMap, pose: FloatArray, cfg: ConeUpdateConfig, matched: IntArray
) -> IntArray:
    """Map cones in range and field of view (from the prior pose) that nothing matched."""
    rot = _rotation(float(pose[2]))
    sensor = pose[:2] + rot @ np.asarray(cfg.sensor_offset)
    near = np.asarray(lmap.tree.query_ball_point(sensor, cfg.max_range), dtype=np.intp)
    if not len(near):
        return _NONE
    rel = (lmap.positions[near] - sensor) @ rot  # into the sensor frame: R' (m - s)
    r = np.hypot(rel[:, 0], rel[:, 1])
    seen = (r >= cfg.min_range) & (np.abs(np.arctan2(rel[:, 1], rel[:, 0])) <= 0.5 * cfg.fov)
    in_view = near[seen]
    return np.sort(in_view[~np.isin(in_view, matched)])


def associate(
    x: FloatArray,
    p: FloatArray,
    points: FloatArray,
    cov: FloatArray,
    *,
    classes: IntArray | None,
    lmap: LandmarkMap,
    cfg: ConeUpdateConfig,
    gate: float,
    bias: int | None = None,
    landmarks: StateCones | None = None,
) -> Association:
    """Match a scan's detections to map cones (module docstring).

    Args:
        x: the prior state, (n, 1).
        p: its covariance, (n, n).
        points: the detections in the sensor frame, (k, 2) [m].
        cov: their covariances in the sensor frame, (k, 2, 2) [m^2].
        classes: their colour classes (-1: unknown), (k,), or None.
        lmap: the map.
        cfg: the settings.
        gate: the pairs' chi-square gate (2 dof).
        bias: the index of ``map_bias_e`` in ``x``, or None.
        landmarks: with the cones in the state (SLAM, ``localization.slam``;
            ``lmap`` holds their positions, and ``x`` and ``p`` may be the
            vehicle's only): their covariance, so each pair's gate takes the
            cone's and its correlation with the pose; else None.
    """
    k = len(points)
    pose = np.array([x.item(X), x.item(Y), x.item(YAW)])
    idx = [X, Y, YAW] if bias is None else [X, Y, YAW, bias, bias + 1]
    pk = p[np.ix_(idx, idx)]
    p3 = pk[:3, :3]
    shift = np.zeros(2) if bias is None else np.array([x.item(bias), x.item(bias + 1)])
    rot = _rotation(float(pose[2]))
    w = pose[:2] + (points + np.asarray(cfg.sensor_offset)) @ rot.T - shift  # on the map
    rw = np.einsum("ij,qjk,lk->qil", rot, cov, rot)
    rho = np.hypot(w[:, 0] - pose[0], w[:, 1] - pose[1])
    reach = rho + 1.0
    bound = (
        p3[0, 0] + p3[1, 1] + p3[2, 2] * reach * reach
        + 2.0 * math.hypot(p3[0, 2], p3[1, 2]) * reach + rw[:, 0, 0] + rw[:, 1, 1]
        + 2.0 * float(np.trace(pk[3:, 3:])) + 2.0 * _largest_cone_variance(landmarks)
    )  # fmt: skip
    radius = np.minimum(np.sqrt(gate * bound), cfg.max_search_radius)
    det, cone = _candidates(lmap, w, radius)
    counts = ConeCounts(scans=1)
    if len(det):
        pair_cov = pk if landmarks is None else _pair_covariance(p3, landmarks, cone)
        d2 = _mahalanobis(pose - [*shift, 0.0], pair_cov, w[det], rw[det], lmap.positions[cone])
        gated = d2 <= gate
        det, cone = det[gated], cone[gated]
    has_geo = np.zeros(k, dtype=bool)
    has_geo[det] = True
    if cfg.use_colours and classes is not None and len(det):
        dc, mc = classes[det], lmap.classes[cone]
        ok = (dc < 0) | (mc < 0) | (dc == mc)
        det, cone = det[ok], cone[ok]
    has_ok = np.zeros(k, dtype=bool)
    has_ok[det] = True
    counts.false_positives = int((~has_geo).sum())
    counts.colour_mismatches = int((has_geo & ~has_ok).sum())
    if len(det) and (np.bincount(det).max() > 1 or np.bincount(cone).max() > 1):
        offset = lmap.positions[cone] - w[det]
        tolerance = cfg.consensus_tolerance + math.sqrt(max(p3[2, 2], 0.0)) * rho[det]
        spread = p3[:2, :2] + pk[3:, 3:] if bias is not None else p3[:2, :2]
        prior_inv = np.asarray(np.linalg.inv(spread + 1e-9 * np.eye(2)), dtype=np.float64)
        det, cone = _consensus(det, cone, offset, tolerance=tolerance, prior_inv=prior_inv, k=k)
        if len(det) < cfg.min_consensus:
            det, cone = _NONE, _NONE
    counts.matched = len(det)
    counts.ambiguous = int(has_ok.sum()) - len(det)
    missed = _missed(lmap, pose, cfg, cone)
    counts.misses = len(missed)
    return Association(det, cone, counts, missed, np.flatnonzero(~has_geo))


def _largest_cone_variance(cones: StateCones | None) -> float:
    """The largest trace of a state cone's 2x2 covariance (0 without cones in the state)."""
    if cones is None or not len(cones.own):
        return 0.0
    return float(np.trace(cones.own, axis1=1, axis2=2).max())


def _pair_covariance(p3: FloatArray, cones: StateCones, cone: IntArray) -> FloatArray:
    """P over (x, y, yaw, cone east, cone north) for each pair's cone, (q, 5, 5)."""
    out = np.empty((len(cone), 5, 5))
    out[:, :3, :3] = p3
    cross = cones.pose[cone]
    out[:, :3, 3:] = cross
    out[:, 3:, :3] = cross.transpose(0, 2, 1)
    out[:, 3:, 3:] = cones.own[cone]
    return out
