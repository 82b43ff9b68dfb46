"""Messages -> checked measurement vectors and covariances for the fusion EKF.

Each converter checks its message before anything reaches the filter, and
raises :class:`InvalidMessage` with a :class:`RejectReason` otherwise:

* the stamp and every value finite (NaN/inf: ``NON_FINITE``);
* the frame the message must be in (``WRONG_FRAME``);
* a GPS fix with a position (status NO_FIX: ``NO_FIX``) on the globe
  (latitude beyond +-90 or longitude beyond +-180 deg: ``OUT_OF_RANGE``);
* a stated covariance that is finite, symmetric (to 1e-9 relative) and
  positive semi-definite (``BAD_COVARIANCE``): a negative variance or a
  non-symmetric matrix is a driver bug, not a very sure sensor.

A sensor that states the *total* variance of an error the filter partly models
as a Gauss-Markov state (``EkfConfig.gps_bias_sigma``, ``heading_bias_sigma``)
gets that part subtracted, and every measurement covariance is floored
(``*_sigma_floor``) so that an ideal sensor stating zero does not make the
covariance singular.

Sensors state the same covariance message after message: each covariance is
built (and a fix's checked) once per distinct stated value, and the read-only
array is shared by the measurements that use it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from conesim.core.geodesy import GeodesyError
from conesim.core.messages import HeadingStamped, Imu, Message, NavSatFix, NavSatStatus, WheelSpeed
from conesim.localization.ekf.config import EkfConfig
from conesim.localization.ekf.health import RejectReason, Sensor
from conesim.localization.ekf.model import wrap_yaw
from conesim.localization.frames.transform import strip_leading_slash
from conesim.localization.gps_to_local import gps_to_local_cartesian

FloatArray = NDArray[np.float64]

SYMMETRY_TOLERANCE = 1e-9  # [-] relative to the largest entry


class InvalidMessage(ValueError):
    """A message the filter must not use.

    Attributes:
        sensor: its stream.
        reason: why.
        stamp: its stamp [s] (may be NaN).
        detail: what exactly was wrong.
    """

    def __init__(self, sensor: Sensor, reason: RejectReason, stamp: float, detail: str) -> None:
        super().__init__(f"{sensor} at {stamp!r} s: {reason}: {detail}")
        self.sensor = sensor
        self.reason = reason
        self.stamp = stamp
        self.detail = detail


@dataclass(frozen=True, slots=True)
class Measurement:
    """A checked message, ready for the filter.

    Attributes:
        sensor: its stream; IMU samples are the filter's input, not a measurement.
        stamp: capture time [s].
        z: measurement (m, 1); for the IMU the input (w_m, a_x, a_y), (3,); for
            a cone scan the detections' (x, y) in the sensor frame, (k, 2) [m].
        cov: measurement covariance (m, m); for the IMU the input's, (3, 3);
            for a cone scan each detection's, (k, 2, 2).
        labels: a cone scan's colour labels (k,), or None.
    """

    sensor: Sensor
    stamp: float
    z: FloatArray
    cov: FloatArray
    labels: tuple[str, ...] | None = None


def _check_header(sensor: Sensor, stamp: float, frame_id: str, expected: str) -> None:
    if not math.isfinite(stamp):
        raise InvalidMessage(sensor, RejectReason.NON_FINITE, stamp, "stamp is not finite")
    if frame_id != expected and strip_leading_slash(frame_id) != expected:  # tf2's names
        detail = f"frame_id {frame_id!r}, expected {expected!r}"
        raise InvalidMessage(sensor, RejectReason.WRONG_FRAME, stamp, detail)


def _check_variance(sensor: Sensor, stamp: float, variance: float, what: str) -> None:
    """A stated variance: finite (NON_FINITE) and >= 0 (BAD_COVARIANCE)."""
    if not math.isfinite(variance):
        raise InvalidMessage(sensor, RejectReason.NON_FINITE, stamp, f"{what} not finite")
    if not variance >= 0.0:
        detail = f"{what} {variance!r} < 0"
        raise InvalidMessage(sensor, RejectReason.BAD_COVARIANCE, stamp, detail)


def _is_diagonal(values: list[float], n: int) -> bool:
    """Whether the row-major (n, n) ``values`` are zero off the diagonal."""
    return all(v == 0.0 for k, v in enumerate(values) if k % (n + 1))


def _check_covariance(sensor: Sensor, stamp: float, cov: FloatArray, what: str) -> None:
    """A stated covariance matrix: finite (NON_FINITE), then symmetric and PSD (BAD_COVARIANCE).

    On floats; a diagonal matrix (the usual case) is PSD iff its diagonal is >= 0,
    anything else goes through ``eigvalsh``.
    """
    n = cov.shape[0]
    values = cov.ravel().tolist()
    if not all(map(math.isfinite, values)):
        raise InvalidMessage(sensor, RejectReason.NON_FINITE, stamp, f"{what} is not finite")
    scale = max(1.0, *map(abs, values))
    tolerance = SYMMETRY_TOLERANCE * scale
    for i in range(n):
        for j in range(i + 1, n):
            if not abs(values[i * n + j] - values[j * n + i]) <= tolerance:
                detail = f"{what} is not symmetric: {cov.tolist()}"
                raise InvalidMessage(sensor, RejectReason.BAD_COVARIANCE, stamp, detail)
    diagonal = values[:: n + 1]
    if _is_diagonal(values, n) and min(diagonal) >= 0.0:
        return
    smallest = float(np.min(np.linalg.eigvalsh(cov)))
    if not (min(diagonal) >= 0.0 and smallest >= -tolerance):
        detail = (
            f"{what} is negative or not positive semi-definite (smallest eigenvalue {smallest!r})"
        )
        raise InvalidMessage(sensor, RejectReason.BAD_COVARIANCE, stamp, detail)


def _floored(cov: FloatArray, floor: float) -> FloatArray:
    """``cov`` raised so that its smallest eigenvalue is at least ``floor``^2.

    A diagonal matrix's eigenvalues are its diagonal (``eigvalsh`` returns
    exactly those), so it skips ``eigvalsh``.
    """
    n = cov.shape[0]
    values = cov.ravel().tolist()
    if _is_diagonal(values, n):
        smallest = min(values[:: n + 1])
    else:
        smallest = float(np.min(np.linalg.eigvalsh(cov)))
    if smallest < floor * floor:
        cov = cov + (floor * floor - smallest) * np.eye(n)
    return cov


def _frozen(a: FloatArray) -> FloatArray:
    a.flags.writeable = False
    return a


# Covariances already built, by everything they are computed from (exact bits: the
# stated values' bytes or the floats with their signs). Sensors state the same
# covariance message after message, so the check, the bias subtraction and the
# floor run once; the (read-only) array is shared by every measurement that uses it.
_COVARIANCES: dict[tuple[object, ...], FloatArray] = {}
_COVARIANCES_SIZE = 64  # entries kept before the cache is cleared


def _remember(key: tuple[object, ...], cov: FloatArray) -> FloatArray:
    """Keep ``cov`` (made read-only) for ``key``, and return it."""
    if len(_COVARIANCES) >= _COVARIANCES_SIZE:
        _COVARIANCES.clear()
    _COVARIANCES[key] = _frozen(cov)
    return cov


def _sign(value: float) -> float:
    """+1.0 or -1.0 (tells 0.0 from -0.0 in a cache key, where the two compare equal)."""
    return math.copysign(1.0, value)


def from_imu(msg: Imu, cfg: EkfConfig) -> Measurement:
    """The filter's input u = (w_m, a_x, a_y) and its per-sample covariance."""
    stamp = msg.header.stamp
    _check_header(Sensor.IMU, stamp, msg.header.frame_id, cfg.antenna_frame)
    w, ax, ay = msg.yaw_rate, msg.accel_x, msg.accel_y
    if not (math.isfinite(w) and math.isfinite(ax) and math.isfinite(ay)):
        raise InvalidMessage(Sensor.IMU, RejectReason.NON_FINITE, stamp, "value not finite")
    _check_variance(Sensor.IMU, stamp, msg.yaw_rate_variance, "yaw_rate_variance")
    _check_variance(Sensor.IMU, stamp, msg.accel_variance, "accel_variance")
    u = np.array((w, ax, ay), dtype=float)
    w_var, a_var = msg.yaw_rate_variance, msg.accel_variance
    key = ("imu", w_var, a_var, _sign(w_var), _sign(a_var))
    cov = _COVARIANCES.get(key)
    if cov is None:
        cov = np.zeros((3, 3))
        cov[0, 0] = w_var
        cov[1, 1] = cov[2, 2] = a_var
        cov = _remember(key, cov)
    return Measurement(Sensor.IMU, stamp, _frozen(u), cov)


def from_fix(msg: NavSatFix, cfg: EkfConfig) -> Measurement:
    """The antenna position in ``reference`` (the ROS pipeline's ``/local_xy``), (2, 1) [m]."""
    stamp = msg.header.stamp
    _check_header(Sensor.GPS, stamp, msg.header.frame_id, cfg.antenna_frame)
    if msg.status == NavSatStatus.NO_FIX:
        raise InvalidMessage(Sensor.GPS, RejectReason.NO_FIX, stamp, "no fix")
    full = np.asarray(msg.position_covariance, dtype=float)
    key = ("fix", full.shape, full.tobytes(), cfg.gps_bias_sigma, cfg.gps_sigma_floor)
    cov = _COVARIANCES.get(key)  # only a covariance that passed the checks is kept
    if cov is None:
        _check_covariance(Sensor.GPS, stamp, full, "position_covariance")
        horizontal = full[:2, :2] - cfg.gps_bias_sigma**2 * np.eye(2)
        cov = _remember(key, _floored(horizontal, cfg.gps_sigma_floor))
    try:
        point = gps_to_local_cartesian(msg, cfg.origin, cfg.reference_frame)
    except GeodesyError as err:
        finite = math.isfinite(msg.latitude) and math.isfinite(msg.longitude)
        reason = RejectReason.OUT_OF_RANGE if finite else RejectReason.NON_FINITE
        raise InvalidMessage(Sensor.GPS, reason, stamp, str(err)) from None
    z = np.array([[point.x], [point.y]])
    return Measurement(Sensor.GPS, stamp, _frozen(z), cov)


def _scalar(
    sensor: Sensor,
    stamp: float,
    value: float,
    variance: float,
    *,
    floor: float,
    bias_sigma: float = 0.0,
) -> Measurement:
    """A checked scalar measurement; its variance less ``bias_sigma``^2, floored."""
    if not math.isfinite(value):
        raise InvalidMessage(sensor, RejectReason.NON_FINITE, stamp, "value not finite")
    _check_variance(sensor, stamp, variance, "variance")
    z = np.array([[value]], dtype=float)
    var = max(variance - bias_sigma * bias_sigma, floor * floor)
    key = ("scalar", var, _sign(var))
    cov = _COVARIANCES.get(key)
    if cov is None:
        cov = _remember(key, np.array([[var]]))
    return Measurement(sensor, stamp, _frozen(z), cov)


def from_heading(msg: HeadingStamped, cfg: EkfConfig) -> Measurement:
    """The heading of ``gps_antenna`` in ``reference``, (1, 1) [rad], wrapped.

    The part of the stated variance that the heading-bias state models is
    subtracted before the floor.
    """
    stamp = msg.header.stamp
    _check_header(Sensor.HEADING, stamp, msg.header.frame_id, cfg.reference_frame)
    yaw = wrap_yaw(msg.yaw) if math.isfinite(msg.yaw) else msg.yaw
    return _scalar(
        Sensor.HEADING,
        stamp,
        yaw,
        msg.variance,
        floor=cfg.heading_sigma_floor,
        bias_sigma=cfg.heading_bias_sigma,
    )


def from_wheel_speed(msg: WheelSpeed, cfg: EkfConfig) -> Measurement:
    """The wheel-encoder speed, (1, 1) [m/s]."""
    stamp = msg.header.stamp
    _check_header(Sensor.WHEEL_SPEED, stamp, msg.header.frame_id, cfg.antenna_frame)
    return _scalar(Sensor.WHEEL_SPEED, stamp, msg.speed, msg.variance, floor=cfg.speed_sigma_floor)


def to_measurement(msg: Message, cfg: EkfConfig) -> Measurement | None:
    """Convert any message; None for the types the filter does not use.

    Raises:
        InvalidMessage: a message of a used type that fails a check.
    """
    if isinstance(msg, Imu):
        return from_imu(msg, cfg)
    if isinstance(msg, NavSatFix):
        return from_fix(msg, cfg)
    if isinstance(msg, HeadingStamped):
        return from_heading(msg, cfg)
    if isinstance(msg, WheelSpeed):
        return from_wheel_speed(msg, cfg)
    return None
