"""Wheel-speed sensor: the vehicle's forward speed from the wheel encoders.

Measurement at capture k [m/s]::

    v_m[k] = s * v[k] + sigma_w * w[k] + sigma_slip * |v[k]| * u[k],
    s = 1 + sigma_s * z   (z ~ N(0, 1), once; w, u ~ N(0, 1) each capture)

The scale factor s (tyre radius error, wear, pressure) is drawn once per
episode from the sensor's own "scale" stream. The slip term is wheel slip
under drive and braking, modelled as white noise in proportion to the speed
(slip ratio std ``slip_sigma``), from its own "slip" stream, so that it
shifts no other draw. The stated variance is sigma_w^2: the encoder's noise,
not the slip.
"""

from __future__ import annotations

from dataclasses import dataclass

from conesim.core.messages import FRAME_GPS_ANTENNA, Header, WheelSpeed
from conesim.sim.sensors.streams import stream
from conesim.sim.sensors.timing import SensorTiming
from conesim.sim.sensors.truth import TruthSample
from conesim.sim.sensors.validation import check_non_negative


@dataclass(frozen=True)
class WheelSpeedConfig(SensorTiming):
    """Wheel-speed settings.

    Attributes:
        white_sigma: white noise std [m/s].
        scale_sigma: std of the per-episode scale error s - 1 [-].
        slip_sigma: std of the wheel slip ratio, white per capture [-].
    """

    rate: float = 50.0  # [Hz]
    latency: float = 0.0  # [s]
    white_sigma: float = 0.05  # [m/s]
    scale_sigma: float = 0.005  # [-]
    slip_sigma: float = 0.0  # [-]

    def _validate(self) -> None:
        check_non_negative("WheelSpeedConfig", "white_sigma", self.white_sigma, "[m/s]")
        check_non_negative("WheelSpeedConfig", "scale_sigma", self.scale_sigma, "[-]")
        check_non_negative("WheelSpeedConfig", "slip_sigma", self.slip_sigma, "[-]")


class WheelSpeedSensor:
    """Simulated wheel-speed sensor publishing ``WheelSpeed`` in ``gps_antenna``.

    Args:
        config: the sensor's settings.
        seed: episode seed (streams "wheel_speed/white", "wheel_speed/scale",
            "wheel_speed/slip").

    Attributes:
        scale: this episode's scale factor s [-].
    """

    name = "wheel_speed"

    def __init__(self, config: WheelSpeedConfig, seed: int) -> None:
        self.config = config
        self.reset(seed)

    def reset(self, seed: int) -> None:
        """Restart the noise stream and draw a new scale factor."""
        self._white = stream(seed, self.name, "white")
        self._slip = stream(seed, self.name, "slip")
        z = float(stream(seed, self.name, "scale").standard_normal())
        self.scale = 1.0 + self.config.scale_sigma * z

    def capture(self, truth: TruthSample) -> WheelSpeed:
        """The speed sample of a capture at ``truth.t``."""
        sigma = self.config.white_sigma
        speed = self.scale * truth.speed + sigma * float(self._white.standard_normal())
        slip = self.config.slip_sigma
        if slip != 0.0:  # drawn only with slip: its own stream, no other draw moves
            speed += slip * abs(truth.speed) * float(self._slip.standard_normal())
        return WheelSpeed(Header(truth.t, FRAME_GPS_ANTENNA), speed, sigma * sigma)
