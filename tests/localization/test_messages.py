"""Tests for localization.messages' checks on construction."""

from __future__ import annotations

import numpy as np
import pytest

from conesim.core.messages import CONE_COLOURS, ConeDetections, Header


def test_cone_detections_take_the_colour_labels_of_cone_colours() -> None:
    """Every label of CONE_COLOURS is taken; 'Blue' (another spelling) and a
    label count that does not match the points are refused by name."""
    points = np.zeros((len(CONE_COLOURS), 3))
    assert len(ConeDetections(Header(0.0, "os_sensor"), points, CONE_COLOURS)) == 5
    with pytest.raises(ValueError, match=r"unknown labels \['Blue'\]; allowed"):
        ConeDetections(Header(0.0, "os_sensor"), points[:2], ("Blue", "yellow"))
    with pytest.raises(ValueError, match="2 labels for 5 points"):
        ConeDetections(Header(0.0, "os_sensor"), points, ("blue", "yellow"))
