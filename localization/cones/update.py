"""The step the fusion EKF calls for a cone scan: checks, association, the stacked model."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.stats import chi2

from conesim.core.messages import ConeDetections
from conesim.localization.cones.association import Association, associate
from conesim.localization.cones.config import ConeUpdateConfig
from conesim.localization.cones.landmarks import LandmarkMap, colour_classes
from conesim.localization.cones.observation import (
    block_diagonal,
    detection_covariance,
    h_cones,
    jacob_h_cones,
)
from conesim.localization.ekf.health import RejectReason, Sensor
from conesim.localization.ekf.measurements import InvalidMessage, Measurement
from conesim.localization.ekf.model import StateLayout
from conesim.localization.frames.transform import strip_leading_slash

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class StackedModel:
    """A scan's associated detections as one measurement for filterpy's update.

    Attributes:
        z: the detections in the sensor frame, stacked, (2a, 1) [m].
        hx: the expected ones, (2a, 1) [m].
        jacobian: H, (2a, n).
        cov: R, block-diagonal, (2a, 2a) [m^2].
    """

    z: FloatArray
    hx: FloatArray
    jacobian: FloatArray
    cov: FloatArray


class ScanUpdate:
    """What every cone-scan update shares: the scan's checks, its covariance, the gates.

    Args:
        config: the detector's noise, gates and colours.
    """

    def __init__(self, config: ConeUpdateConfig | None = None) -> None:
        self.config = config or ConeUpdateConfig()
        self.pair_gate = float(chi2.ppf(self.config.gate_probability, 2))
        self._joint_gates: dict[int, float] = {}
        self._bands: dict[int, tuple[float, float]] = {}

    def joint_gate(self, dof: int) -> float:
        """The joint NIS gate of a ``dof``-dimensional stacked update."""
        gate = self._joint_gates.get(dof)
        if gate is None:
            gate = self._joint_gates[dof] = float(chi2.ppf(self.config.gate_probability, dof))
        return gate

    def nis_band(self, dof: int) -> tuple[float, float]:
        """The two-sided 95 % chi-square band of a ``dof``-dimensional update's NIS."""
        band = self._bands.get(dof)
        if band is None:
            band = self._bands[dof] = (float(chi2.ppf(0.025, dof)), float(chi2.ppf(0.975, dof)))
        return band

    def measurement(self, msg: ConeDetections) -> Measurement:
        """The scan as a measurement: points (k, 2), their covariances, colour labels.

        Raises:
            InvalidMessage: a stamp or point that is not finite, or another frame.
        """
        stamp = msg.header.stamp
        frame = msg.header.frame_id
        if not math.isfinite(stamp):
            raise InvalidMessage(Sensor.CONES, RejectReason.NON_FINITE, stamp, "stamp not finite")
        expected = self.config.sensor_frame
        if frame != expected and strip_leading_slash(frame) != expected:
            detail = f"frame_id {frame!r}, expected {expected!r}"
            raise InvalidMessage(Sensor.CONES, RejectReason.WRONG_FRAME, stamp, detail)
        points = np.array(np.asarray(msg.points, dtype=float)[:, :2])
        if not np.isfinite(points).all():
            raise InvalidMessage(Sensor.CONES, RejectReason.NON_FINITE, stamp, "point not finite")
        points.setflags(write=False)
        cov = detection_covariance(points, self.config)
        cov.setflags(write=False)
        return Measurement(Sensor.CONES, stamp, points, cov, msg.colours)


class ConeUpdate(ScanUpdate):
    """Cone scans against a map, for :class:`~localization.ekf.filter.FusionEkf`.

    Args:
        landmarks: the map.
        config: the detector's noise, gates and colours.
    """

    def __init__(self, landmarks: LandmarkMap, config: ConeUpdateConfig | None = None) -> None:
        super().__init__(config)
        self.landmarks = landmarks

    def associate(
        self, x: FloatArray, p: FloatArray, meas: Measurement, layout: StateLayout
    ) -> Association:
        """Match the scan's detections to the map with the prior (x, P) on ``layout``."""
        classes = None if meas.labels is None else colour_classes(meas.labels)
        return associate(
            x, p, meas.z, meas.cov, classes=classes, lmap=self.landmarks,
            cfg=self.config, gate=self.pair_gate, bias=layout.map_bias_index,
        )  # fmt: skip

    def model(
        self, x: FloatArray, meas: Measurement, found: Association, layout: StateLayout
    ) -> StackedModel:
        """z, h(x), H and R of the associated detections, stacked."""
        cones = self.landmarks.positions[found.landmarks]
        bias = layout.map_bias_index
        return StackedModel(
            z=meas.z[found.detections].reshape(-1, 1),
            hx=h_cones(x, cones, self.config.sensor_offset, bias),
            jacobian=jacob_h_cones(x, cones, layout.n, bias),
            cov=block_diagonal(meas.cov[found.detections]),
        )
