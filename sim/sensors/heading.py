"""Heading sensor: ``/global_yaw`` as a dual-antenna GNSS gives it.

Measurement at capture k, in ``reference`` [rad]::

    yaw_m[k] = wrap(yaw[k] + b[k] + sigma_w * v[k])      v ~ N(0, 1)

with an optional first-order Gauss-Markov bias b (``noise.GaussMarkov``,
stationary std ``bias_sigma``, correlation time ``bias_tau``), wrapped into
[-pi, pi). The stated variance is the stationary total sigma_w^2 + sigma_b^2.

Dropouts: a capture whose stamp falls in a window of ``dropouts`` (start
[s], duration [s]) publishes nothing (a dual-antenna receiver that has lost
one antenna's carrier). The noise draws advance at every capture whatever
the dropouts, so a dropout changes no other heading.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from conesim.core.messages import FRAME_REFERENCE, Header, HeadingStamped
from conesim.core.pose import wrap_angle
from conesim.sim.sensors.noise import GaussMarkov
from conesim.sim.sensors.streams import stream
from conesim.sim.sensors.timing import SensorTiming
from conesim.sim.sensors.truth import TruthSample
from conesim.sim.sensors.validation import check_non_negative, check_positive
from conesim.sim.sensors.windows import Windows, check_windows, in_windows


@dataclass(frozen=True)
class HeadingConfig(SensorTiming):
    """Heading sensor settings.

    Attributes:
        white_sigma: white noise std [rad].
        bias_sigma: stationary std of the Gauss-Markov bias [rad].
        bias_tau: correlation time of the bias [s], > 0.
        dropouts: windows (start [s], duration [s]) of capture time without a heading.
    """

    rate: float = 20.0  # [Hz]
    latency: float = 0.05  # [s]
    white_sigma: float = math.radians(0.25)  # [rad]
    bias_sigma: float = 0.0  # [rad]
    bias_tau: float = 60.0  # [s]
    dropouts: Windows = ()  # ((start [s], duration [s]), ...)

    def _validate(self) -> None:
        check_non_negative("HeadingConfig", "white_sigma", self.white_sigma, "[rad]")
        check_non_negative("HeadingConfig", "bias_sigma", self.bias_sigma, "[rad]")
        check_positive("HeadingConfig", "bias_tau", self.bias_tau, "[s]")
        check_windows("HeadingConfig", "dropouts", self.dropouts)


class HeadingSensor:
    """Simulated dual-antenna heading publishing ``HeadingStamped`` in ``reference``.

    Args:
        config: the sensor's settings.
        seed: episode seed (streams "heading/white", "heading/bias").
    """

    name = "heading"

    def __init__(self, config: HeadingConfig, seed: int) -> None:
        self.config = config
        self.reset(seed)

    def reset(self, seed: int) -> None:
        """Restart the noise streams and the bias from ``seed``."""
        self._white = stream(seed, self.name, "white")
        self._bias = GaussMarkov(
            self.config.bias_sigma, self.config.bias_tau, stream(seed, self.name, "bias")
        )
        self._last_t: float | None = None

    def capture(self, truth: TruthSample) -> HeadingStamped | None:
        """The heading of a capture at ``truth.t``, or None in a dropout."""
        cfg = self.config
        bias = self._bias.state if self._last_t is None else self._bias.step(truth.t - self._last_t)
        self._last_t = truth.t
        noise = bias[0] + cfg.white_sigma * float(self._white.standard_normal())
        if cfg.dropouts and in_windows(truth.t, cfg.dropouts):
            return None
        yaw = float(wrap_angle(truth.antenna_pose.yaw + noise))
        variance = cfg.white_sigma**2 + cfg.bias_sigma**2
        return HeadingStamped(Header(truth.t, FRAME_REFERENCE), yaw, variance)
