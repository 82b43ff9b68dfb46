"""Cone detector: the ROS pipeline's ``/sorted_cones_time``, cones in ``os_sensor``.

A scan at capture time t, with the vehicle at the antenna pose (``os_sensor``
has the same planar pose, 0.1 m lower):

1. Geometry. Each cone within ``max_range`` goes into ``os_sensor``:
   (x, y) = R(yaw)^T (p - p_antenna), r = |(x, y)|, b = atan2(y, x). It is
   visible when min_range <= r <= max_range, |b| <= fov / 2 and, with
   ``occlusion``, it is not behind a nearer cone (``occlusion.py``).
2. Detection. A visible cone is detected with probability
   p(r) = clip(p0 - k r, 0, 1) (fssim: p0 = 1, k = 0.01 / m, i.e. 1 - r/100).
3. Noise. Range and bearing get white noise::

       r_m = r + sigma_r n1,   b_m = b + sigma_b n2
       (x_m, y_m) = (r_m / r) R(b_m - b) (x, y)

   which equals (x, y) bit for bit when both sigmas are zero.
4. False positives. N ~ Poisson(lambda) points per scan, uniform over the
   area of the field of view: r = sqrt(U(r_min^2, r_max^2)), b = U(-fov/2, fov/2).
5. Colour (optional, ``cone_colour.py``): recognised only within
   ``colour_range`` with probability ``colour_probability``, then drawn from
   the confusion matrix; otherwise "unknown".

z of a point is the cone's mid-height relative to ``os_sensor``:
height / 2 - sensor_height (ground at -sensor_height; the planner uses x, y
only). Points are sorted by their measured planar distance. The message is
stamped at capture and delivered after ``latency`` (the suite's job).

Each step draws from its own stream ("cones/detect", "cones/range",
"cones/bearing", "cones/false_positive", "cones/colour").
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from conesim.core.messages import CONE_COLOURS, FRAME_OS_SENSOR, ConeDetections, Header
from conesim.sim.sensors.cone_colour import (
    IDENTITY_CONFUSION,
    KIND_TO_CLASS,
    check_confusion,
    sample_colours,
)
from conesim.sim.sensors.cone_map import (
    SMALL_CONE_HEIGHT,
    cone_heights,
    cone_radii,
    kind_codes,
)
from conesim.sim.sensors.occlusion import occluded
from conesim.sim.sensors.streams import stream
from conesim.sim.sensors.timing import SensorTiming
from conesim.sim.sensors.truth import TruthSample
from conesim.sim.sensors.validation import (
    check_closed,
    check_interval,
    check_non_negative,
    check_positive,
    check_probability,
)

MAX_FALSE_POSITIVES = 100.0  # [1/scan] a bound on the ghost cones a scan may hold (a
# real LiDAR pipeline reports tens of cones; 1e9 would take 15 GB per scan)

# Colour class of each entry of CONE_COLOURS (big_orange -> the orange row).
_CODE_TO_CLASS = np.array([KIND_TO_CLASS[k] for k in CONE_COLOURS], dtype=np.intp)
_BIG_CODE = CONE_COLOURS.index("big_orange")
_UNKNOWN_CODE = CONE_COLOURS.index("unknown")
_NO_POINTS = np.zeros((0, 2))
_NO_POINTS.setflags(write=False)
_NO_RANGES = np.zeros(0)
_NO_RANGES.setflags(write=False)


@dataclass(frozen=True)
class ConeDetectorConfig(SensorTiming):
    """Cone detector settings (defaults: the fssim LiDAR, see ``profiles.py``).

    Attributes:
        min_range: nearest detectable cone [m], in [0, max_range].
        max_range: farthest detectable cone [m], > 0.
        fov: total horizontal field of view centred on +x [rad], in (0, 2 pi].
        range_sigma: white range noise std [m].
        bearing_sigma: white bearing noise std [rad].
        detection_probability_at_zero: p0 of p(r) = clip(p0 - k r, 0, 1).
        detection_probability_slope: k of the same law [1/m], >= 0.
        false_positive_rate: mean false positives per scan (Poisson), at most
            ``MAX_FALSE_POSITIVES`` [1/scan].
        report_colour: attach colour labels (False: a colour-blind detector).
        colour_range: colour recognised only up to this range [m] (inf allowed).
        colour_probability: chance a cone in colour range is recognised.
        confusion: 4x4 row-stochastic matrix over (blue, yellow, orange,
            unknown), rows = true class, columns = reported class.
        report_big_orange: label big orange cones "big_orange" (else "orange").
        occlusion: hide cones behind nearer cones.
        sensor_height: height of ``os_sensor`` above the ground [m].
    """

    rate: float = 10.0  # [Hz]
    latency: float = 0.2  # [s]
    min_range: float = 1.0  # [m]
    max_range: float = 15.0  # [m]
    fov: float = math.pi  # [rad]
    range_sigma: float = 0.05  # [m]
    bearing_sigma: float = 0.007  # [rad]
    detection_probability_at_zero: float = 1.0  # [-]
    detection_probability_slope: float = 0.01  # [1/m]
    false_positive_rate: float = 0.0  # [1/scan]
    report_colour: bool = True
    colour_range: float = 10.0  # [m]
    colour_probability: float = 0.8  # [-]
    confusion: tuple[tuple[float, ...], ...] = IDENTITY_CONFUSION
    report_big_orange: bool = True
    occlusion: bool = True
    sensor_height: float = 1.0  # [m]

    def _validate(self) -> None:
        owner = "ConeDetectorConfig"
        check_positive(owner, "max_range", self.max_range, "[m]")
        if not (math.isfinite(self.min_range) and 0.0 <= self.min_range <= self.max_range):
            raise ValueError(
                f"{owner}.min_range = {self.min_range!r} is out of range: "
                f"allowed [0, max_range = {self.max_range:g}] [m]"
            )
        check_interval(owner, "fov", self.fov, low=0.0, high=2.0 * math.pi, unit="[rad]")
        check_non_negative(owner, "range_sigma", self.range_sigma, "[m]")
        check_non_negative(owner, "bearing_sigma", self.bearing_sigma, "[rad]")
        check_probability(
            owner, "detection_probability_at_zero", self.detection_probability_at_zero
        )
        check_non_negative(
            owner, "detection_probability_slope", self.detection_probability_slope, "[1/m]"
        )
        check_closed(
            owner, "false_positive_rate", self.false_positive_rate,
            low=0.0, high=MAX_FALSE_POSITIVES, unit="[1/scan]",
        )  # fmt: skip
        if not self.colour_range >= 0.0:
            raise ValueError(
                f"{owner}.colour_range = {self.colour_range!r} is out of range: "
                "allowed [0, inf] [m]"
            )
        check_probability(owner, "colour_probability", self.colour_probability)
        object.__setattr__(
            self, "confusion", tuple(tuple(float(v) for v in row) for row in self.confusion)
        )
        check_confusion(owner, "confusion", self.confusion)
        if not math.isfinite(self.sensor_height):
            raise ValueError(
                f"{owner}.sensor_height = {self.sensor_height!r} is out of range: "
                "allowed a finite height [m]"
            )

    def detection_probability(self, r: NDArray[np.float64]) -> NDArray[np.float64]:
        """p(r) = clip(p0 - k r, 0, 1) for ranges ``r`` [m]."""
        p0, k = self.detection_probability_at_zero, self.detection_probability_slope
        return np.clip(p0 - k * r, 0.0, 1.0)


class ConeDetector:
    """Simulated cone detector publishing ``ConeDetections`` in ``os_sensor``.

    Args:
        config: the detector's settings.
        seed: episode seed.
    """

    name = "cones"

    def __init__(self, config: ConeDetectorConfig, seed: int) -> None:
        self.config = config
        self._cdf_of: tuple[tuple[float, ...], ...] | None = None
        self._cdf = np.empty((4, 4))
        self.reset(seed)

    def reset(self, seed: int) -> None:
        """Restart the detector's streams from ``seed``."""
        self._detect = stream(seed, self.name, "detect")
        self._range = stream(seed, self.name, "range")
        self._bearing = stream(seed, self.name, "bearing")
        self._false = stream(seed, self.name, "false_positive")
        self._colour = stream(seed, self.name, "colour")

    def _confusion_cdf(self) -> NDArray[np.float64]:
        """Row-wise cumulative confusion matrix (4, 4), cached per matrix."""
        confusion = self.config.confusion
        if self._cdf_of is not confusion:
            cdf = np.cumsum(np.asarray(confusion, dtype=float), axis=1)
            cdf[:, -1] = 1.0  # rows sum to 1 within 1e-9: the last bin catches every u < 1
            self._cdf, self._cdf_of = cdf, confusion
        return self._cdf

    @staticmethod
    def _candidates(
        truth: TruthSample, max_range: float
    ) -> tuple[NDArray[np.intp], NDArray[np.float64], NDArray[np.float64], NDArray[np.intp]]:
        """Cones within ``max_range`` of the sensor: indices, radii, heights, kind codes."""
        centre = (truth.antenna_pose.x, truth.antenna_pose.y)
        cmap = truth.cone_map
        if cmap is not None:
            idx = cmap.query(centre, max_range)
            return idx, cmap.radii[idx], cmap.heights[idx], cmap.codes[idx]
        d2 = np.sum((truth.cone_positions - centre) ** 2, axis=1)
        idx = np.flatnonzero(d2 <= max_range * max_range)
        kinds = [truth.cone_kinds[i] for i in idx]
        return idx, cone_radii(kinds), cone_heights(kinds), kind_codes(kinds)

    def capture(self, truth: TruthSample) -> ConeDetections:
        """The detections of a scan at ``truth.t``."""
        cfg = self.config
        idx, radii, heights, codes = self._candidates(truth, cfg.max_range)
        local = truth.antenna_pose.inverse_transform_points(truth.cone_positions[idx])
        r = np.hypot(local[:, 0], local[:, 1])
        b = np.arctan2(local[:, 1], local[:, 0])
        visible = (r >= cfg.min_range) & (r <= cfg.max_range) & (np.abs(b) <= 0.5 * cfg.fov)
        if cfg.occlusion:
            visible &= ~occluded(r, b, radii, visible)
        vis = np.flatnonzero(visible)
        sel = vis if self._sure_detection() else self._detected(vis, r[vis])

        r_sel = r[sel]
        xy = self._add_noise(local[sel], r_sel)
        fp_xy, fp_r = self._false_positives()
        if fp_r.size:
            points_xy = np.vstack([xy, fp_xy])
            true_r = np.concatenate([r_sel, fp_r])
            z = (
                np.concatenate([0.5 * heights[sel], np.full(fp_r.size, 0.5 * SMALL_CONE_HEIGHT)])
                - cfg.sensor_height
            )
            det_codes = np.concatenate([codes[sel], np.full(fp_r.size, _UNKNOWN_CODE, np.intp)])
        else:  # the same values without stacking empty arrays (most scans)
            points_xy, true_r = xy, r_sel
            z = 0.5 * heights[sel] - cfg.sensor_height
            det_codes = codes[sel]
        colours = None
        if cfg.report_colour:
            colours = self._colours(det_codes, true_r)

        order = np.argsort(np.hypot(points_xy[:, 0], points_xy[:, 1]), kind="stable")
        points = np.empty((z.size, 3))
        points[:, :2] = points_xy
        points[:, 2] = z
        points = points[order]
        if colours is not None:
            colours = tuple(colours[i] for i in order.tolist())
        return ConeDetections(Header(truth.t, FRAME_OS_SENSOR), points, colours)

    def _sure_detection(self) -> bool:
        """Whether p(r) is 1 at every range (p0 >= 1, k = 0, the ideal profile):
        every visible cone is detected, and nothing is drawn (the stream is
        the detection's own, so no other draw moves)."""
        cfg = self.config
        return cfg.detection_probability_at_zero >= 1.0 and cfg.detection_probability_slope == 0.0

    def _detected(self, vis: NDArray[np.intp], r: NDArray[np.float64]) -> NDArray[np.intp]:
        """The visible cones ``vis`` at ranges ``r`` [m] that the draws detect, p(r) each."""
        return vis[self._detect.random(vis.size) < self.config.detection_probability(r)]

    def _add_noise(self, xy: NDArray[np.float64], r: NDArray[np.float64]) -> NDArray[np.float64]:
        """Range and bearing noise on (m, 2) points at ranges (m,) [m].

        Without noise (both sigmas zero, the ideal profile) the points
        themselves, and nothing is drawn: the formula gives them bit for bit
        (a scale of 1, a rotation by a signed zero), the streams are the
        noise's own.
        """
        cfg = self.config
        if cfg.range_sigma == 0.0 and cfg.bearing_sigma == 0.0:
            return xy
        dr = cfg.range_sigma * self._range.standard_normal(r.size)
        db = cfg.bearing_sigma * self._bearing.standard_normal(r.size)
        scale = 1.0 + np.divide(dr, r, out=np.zeros_like(dr), where=r > 0.0)
        c, s = np.cos(db), np.sin(db)
        out = np.empty((r.size, 2))
        x0, y0 = xy[:, 0], xy[:, 1]
        out[:, 0] = scale * (c * x0 - s * y0)
        out[:, 1] = scale * (s * x0 + c * y0)
        return out

    def _false_positives(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Poisson-many points uniform over the field of view: (k, 2) [m], (k,) ranges."""
        cfg = self.config
        n = int(self._false.poisson(cfg.false_positive_rate))
        if n == 0:  # (drawing none would not move the stream either)
            return _NO_POINTS, _NO_RANGES
        u = self._false.random((n, 2))
        r = np.sqrt(cfg.min_range**2 + u[:, 0] * (cfg.max_range**2 - cfg.min_range**2))
        b = (u[:, 1] - 0.5) * cfg.fov
        return np.column_stack([r * np.cos(b), r * np.sin(b)]), r

    def _colours(self, codes: NDArray[np.intp], true_r: NDArray[np.float64]) -> tuple[str, ...]:
        """Labels of detections with ``CONE_COLOURS`` codes (n,) at true ranges (n,) [m]."""
        cfg = self.config
        u = self._colour.random((codes.size, 2))
        coloured = (true_r <= cfg.colour_range) & (u[:, 0] < cfg.colour_probability)
        return sample_colours(
            _CODE_TO_CLASS[codes],
            codes == _BIG_CODE,
            coloured,
            u[:, 1],
            confusion_cdf=self._confusion_cdf(),
            report_big_orange=cfg.report_big_orange,
        )
