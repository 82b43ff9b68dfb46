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


LOCALIZATION_MODES = tuple(mode.value for mode in LocalizationMode)
"""The modes' names: ``fused``, ``raw``, ``truth``."""
