"""GNSS receiver model: a NavSatFix-like fix of ``gps_antenna`` at ``rate``.

Error model, per axis (east, north) in ``reference`` [m], at capture k::

    e[k] = b[k] + sigma_w * v[k] (+ o[k])        v ~ N(0, 1) white
    b[k+1] = phi b[k] + sigma_b sqrt(1 - phi^2) w[k],  phi = exp(-dt / tau)

(a first-order Gauss-Markov bias, ``noise.GaussMarkov``, dt = time between
captures), so the stationary per-axis std is sqrt(sigma_w^2 + sigma_b^2). The
fix is ``local_cartesian_to_gps(x + e_x, y + e_y)``: the exact inverse of the
reference pipeline's projection, so ``gps_to_local_cartesian`` of a noise-free fix returns
the antenna position. Altitude is the origin's (a 2D simulator).

The reported ``position_covariance`` is what a receiver states, not the truth:
diag(s^2, s^2, (2 s)^2) with s = ``reported_sigma`` (default: the stationary
total above; vertical GNSS error taken as twice horizontal, an assumption).

Faults. Multipath: with probability ``multipath_probability`` a fix is
displaced by exactly ``multipath_magnitude`` metres in a uniformly random
direction (o[k]). Bias drift: from ``drift_start`` on, the fix moves away
from the truth at ``drift_rate`` (east, north) [m/s], d[k] = rate (t - start),
added to e[k] (a solution that walks off, as an RTK fix falling back to a
float solution does); the stated covariance does not grow with it.
Dropouts: during a window [start, start + duration) of the capture stamp
the receiver either publishes fixes with status NO_FIX and NaN position and
covariance (``dropout_mode="no_fix"``, as the u-blox driver keeps publishing
when the fix is lost) or nothing (``"silent"``). The noise processes and the
multipath draws advance at every capture whatever the faults, and each comes
from its own stream, so switching a fault on changes no other fix.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from conesim.core.geodesy import (
    DEFAULT_ORIGIN,
    R_EARTH,
    ReferenceOrigin,
    local_cartesian_to_gps,
)
from conesim.core.messages import FRAME_GPS_ANTENNA, Header, NavSatFix, NavSatStatus
from conesim.sim.sensors.noise import GaussMarkov
from conesim.sim.sensors.streams import stream
from conesim.sim.sensors.timing import SensorTiming
from conesim.sim.sensors.truth import TruthSample
from conesim.sim.sensors.validation import (
    check_choice,
    check_non_negative,
    check_pair,
    check_positive,
    check_probability,
)
from conesim.sim.sensors.windows import Windows, check_windows, in_windows

DROPOUT_MODES = ("no_fix", "silent")
VERTICAL_TO_HORIZONTAL = 2.0  # [-] reported vertical sigma / horizontal (assumption)


@dataclass(frozen=True)
class GpsConfig(SensorTiming):
    """GNSS receiver settings (see the module docstring for the model).

    Attributes:
        white_sigma: white noise std per axis [m].
        bias_sigma: stationary std of the Gauss-Markov bias per axis [m].
        bias_tau: correlation time of the bias [s], > 0.
        reported_sigma: per-axis sigma the receiver states [m]; None for the
            true stationary total sqrt(white_sigma^2 + bias_sigma^2).
        fix_status: status of a good fix (FIX, SBAS_FIX or GBAS_FIX for RTK).
        dropouts: windows (start [s], duration [s]) without a fix.
        dropout_mode: "no_fix" (NO_FIX messages) or "silent" (no message).
        multipath_probability: chance that a fix is an outlier, [0, 1].
        multipath_magnitude: size of an outlier's displacement [m].
        drift_rate: (east, north) rate of the bias drift [m/s].
        drift_start: capture time the drift starts from [s].
    """

    rate: float = 10.0  # [Hz]
    latency: float = 0.05  # [s]
    white_sigma: float = 0.02  # [m]
    bias_sigma: float = 0.0  # [m]
    bias_tau: float = 60.0  # [s]
    reported_sigma: float | None = None  # [m]
    fix_status: NavSatStatus = NavSatStatus.FIX
    dropouts: Windows = ()  # ((start [s], duration [s]), ...)
    dropout_mode: str = "no_fix"
    multipath_probability: float = 0.0  # [-]
    multipath_magnitude: float = 20.0  # [m]
    drift_rate: tuple[float, float] = (0.0, 0.0)  # [m/s] (east, north)
    drift_start: float = 0.0  # [s]

    def _validate(self) -> None:
        owner = "GpsConfig"
        check_non_negative(owner, "white_sigma", self.white_sigma, "[m]")
        check_non_negative(owner, "bias_sigma", self.bias_sigma, "[m]")
        check_positive(owner, "bias_tau", self.bias_tau, "[s]")
        if self.reported_sigma is not None:
            check_non_negative(owner, "reported_sigma", self.reported_sigma, "[m]")
        if self.fix_status == NavSatStatus.NO_FIX:
            raise ValueError(
                "GpsConfig.fix_status = NO_FIX is out of range: allowed FIX, SBAS_FIX, GBAS_FIX"
            )
        check_windows(owner, "dropouts", self.dropouts)
        check_choice(owner, "dropout_mode", self.dropout_mode, DROPOUT_MODES)
        check_probability(owner, "multipath_probability", self.multipath_probability)
        check_non_negative(owner, "multipath_magnitude", self.multipath_magnitude, "[m]")
        rate = check_pair(owner, "drift_rate", self.drift_rate, "(east, north) [m/s]")
        object.__setattr__(self, "drift_rate", rate)
        check_non_negative(owner, "drift_start", self.drift_start, "[s]")

    @property
    def total_sigma(self) -> float:
        """True stationary per-axis std sqrt(white^2 + bias^2) [m]."""
        return math.hypot(self.white_sigma, self.bias_sigma)

    def in_dropout(self, t: float) -> bool:
        """Whether capture time ``t`` [s] falls in a dropout window."""
        return in_windows(t, self.dropouts)


class GpsReceiver:
    """Simulated GNSS receiver publishing ``NavSatFix`` in ``gps_antenna``.

    Args:
        config: the receiver's settings.
        seed: episode seed (streams "gps/white", "gps/bias", "gps/multipath").
        origin: geodetic origin of ``reference``.
    """

    name = "gps"

    def __init__(
        self, config: GpsConfig, seed: int, origin: ReferenceOrigin = DEFAULT_ORIGIN
    ) -> None:
        self.config = config
        self.origin = origin
        self._cov_cache: tuple[GpsConfig, NDArray[np.float64]] | None = None
        self.reset(seed)

    def reset(self, seed: int) -> None:
        """Restart the noise streams and the bias from ``seed``."""
        self._white = stream(seed, self.name, "white")
        self._multipath = stream(seed, self.name, "multipath")
        self._bias = GaussMarkov(
            self.config.bias_sigma, self.config.bias_tau, stream(seed, self.name, "bias"), dim=2
        )
        self._last_t: float | None = None

    def _draw_error(self, t: float) -> tuple[float, float]:
        """Draw the east/north error [m] of a capture at ``t`` [s] (plain floats)."""
        bias = self._bias.state if self._last_t is None else self._bias.step(t - self._last_t)
        self._last_t = t
        cfg = self.config
        w0, w1 = self._white.standard_normal(2).tolist()
        ex, ey = bias[0] + cfg.white_sigma * w0, bias[1] + cfg.white_sigma * w1
        u, angle = self._multipath.random(2).tolist()
        if u < cfg.multipath_probability:
            mag = cfg.multipath_magnitude
            ex += mag * math.cos(2 * math.pi * angle)
            ey += mag * math.sin(2 * math.pi * angle)
        rate = cfg.drift_rate
        if rate != (0.0, 0.0) and t > cfg.drift_start:  # without a drift: e itself
            ex += rate[0] * (t - cfg.drift_start)
            ey += rate[1] * (t - cfg.drift_start)
        return ex, ey

    def _covariance(self) -> NDArray[np.float64]:
        """The stated (3, 3) covariance of the current config, built once per config
        (read-only: every fix of the config shares it)."""
        cfg = self.config
        cached = self._cov_cache
        if cached is None or cached[0] is not cfg:
            s = cfg.total_sigma if cfg.reported_sigma is None else cfg.reported_sigma
            cov = np.diag([s * s, s * s, (VERTICAL_TO_HORIZONTAL * s) ** 2])
            cov.flags.writeable = False
            cached = self._cov_cache = (cfg, cov)
        return cached[1]

    def capture(self, truth: TruthSample) -> NavSatFix | None:
        """The fix of a capture at ``truth.t``, or None in a silent dropout."""
        cfg = self.config
        ex, ey = self._draw_error(truth.t)
        header = Header(stamp=truth.t, frame_id=FRAME_GPS_ANTENNA)
        if cfg.in_dropout(truth.t):
            if cfg.dropout_mode == "silent":
                return None
            nan = math.nan
            return NavSatFix(
                header, nan, nan, nan, np.full((3, 3), nan), status=NavSatStatus.NO_FIX
            )
        pose = truth.antenna_pose
        lat, lon = self._to_gps(pose.x + ex, pose.y + ey)
        return NavSatFix(header, lat, lon, self.origin.alt_m, self._covariance(), cfg.fix_status)

    def _to_gps(self, x: float, y: float) -> tuple[float, float]:
        """``local_cartesian_to_gps`` of one point on plain floats: (lat, lon) [deg].

        The same operations (``math.degrees`` multiplies by 180 / pi as
        ``np.degrees`` does); anything out of range goes to the library
        function, which raises its error.
        """
        origin = self.origin
        ref_lat_r, ref_lon_r = math.radians(origin.lat_deg), math.radians(origin.lon_deg)
        lat = math.degrees(y / R_EARTH + ref_lat_r)
        lon = math.degrees(x / (R_EARTH * math.cos(ref_lat_r)) + ref_lon_r)
        if abs(lat) <= 90.0 and abs(lon) <= 180.0:  # False for NaN and inf
            return lat, lon
        lat_a, lon_a = local_cartesian_to_gps(x, y, origin)
        return float(lat_a), float(lon_a)
