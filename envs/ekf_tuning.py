"""Which EKF tuning a sensor profile gets, when no tuning is given.

The filter's settings (``localization.ekf.EkfConfig``) are of two kinds.
Some describe the sensors, as a team would characterise its own receiver:
the IMU's rate and the receiver's correlated errors (the GPS and heading
Gauss-Markov biases, their sigma and tau). The others are the filter's own
tuning: process noise, gating, initialisation, history. ``localization``
cannot see the sensor models (it never imports ``sim``), so the match is
made here, in ``envs``, where both meet:

* the tuning: the profile's own (``localization.ekf.PROFILES``) when its
  name is a shipped profile's, else ``rtk``'s;
* the sensor description: taken from the profile itself, so a profile
  changed by an override (a GPS bias on rtk sensors, say) gets a filter
  that models it. For every shipped profile this is exactly its shipped
  tuning (a test holds them equal).

Faults are applied after the match (``envs.scenario``): the filter is told
what the sensors are, not what goes wrong with them. The cone update
(``cones`` mode) is matched the same way to the cone detector
(``matched_cone_update``).
"""

from __future__ import annotations

import dataclasses

from conesim.localization.cones import ConeUpdateConfig
from conesim.localization.ekf import PROFILES as EKF_PROFILES
from conesim.localization.ekf import EkfConfig, for_profile
from conesim.sim.sensors import DEFAULT_PROFILE, SensorProfile


def tuning_name(profile: SensorProfile) -> str:
    """The shipped EKF tuning a profile starts from: its own name's, else rtk's."""
    return profile.name if profile.name in EKF_PROFILES else DEFAULT_PROFILE


def matched_ekf(profile: SensorProfile, tuning: str | None = None) -> EkfConfig:
    """The EKF settings for ``profile`` (see the module docstring).

    Args:
        profile: the sensors as the team knows them (before any fault).
        tuning: the shipped tuning to start from; None: ``tuning_name(profile)``.

    Raises:
        ValueError: an unknown tuning (the message lists the shipped ones).
    """
    base = for_profile(tuning or tuning_name(profile))
    gps, heading = profile.gps, profile.heading
    return dataclasses.replace(
        base,
        imu_rate=profile.imu.rate,
        gps_bias_sigma=gps.bias_sigma,
        gps_bias_tau=gps.bias_tau,
        heading_bias_sigma=heading.bias_sigma,
        heading_bias_tau=heading.bias_tau,
    )


def matched_cone_update(profile: SensorProfile) -> ConeUpdateConfig:
    """The cone update's settings for ``profile``'s cone detector (``cones`` mode).

    The detector's range and bearing noise and its field of view, as the team
    knows them (before any fault); the gates and the map's assumed error are
    ``ConeUpdateConfig``'s defaults.
    """
    cones = profile.cones
    return ConeUpdateConfig(
        range_sigma=cones.range_sigma,
        bearing_sigma=cones.bearing_sigma,
        min_range=cones.min_range,
        max_range=cones.max_range,
        fov=cones.fov,
    )
