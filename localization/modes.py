"""Where the frame tree's ``reference -> gps_antenna`` pose comes from.

A module of its own, importing nothing heavy, so that the command line can
list the modes without loading the filter and its compiled kernels.
"""

from __future__ import annotations

from enum import StrEnum


class LocalizationMode(StrEnum):
    """The localization modes (``localization.localizer``, ``localization.broadcaster``)."""

    FUSED = "fused"
    """The fusion EKF's estimate (default)."""
    RAW = "raw"
    """The ROS pipeline as written: the last ``/local_xy`` and ``/global_yaw``."""
    TRUTH = "truth"
    """The true pose (a baseline and a debugging aid)."""
    CONES = "cones"
    """The fusion EKF with each cone scan matched to a known cone map (``localization.cones``)."""
    SLAM = "slam"
    """The fusion EKF building the cone map as it drives: EKF-SLAM (``localization.slam``)."""

    @property
    def uses_ekf(self) -> bool:
        """Whether the broadcaster publishes the fusion EKF's estimate."""
        return self in (LocalizationMode.FUSED, LocalizationMode.CONES, LocalizationMode.SLAM)


LOCALIZATION_MODES = tuple(mode.value for mode in LocalizationMode)
"""The modes' names: ``fused``, ``raw``, ``truth``, ``cones``, ``slam``."""
