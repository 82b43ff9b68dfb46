"""The settings groups the kernels read: built once, by name, one type per field."""

from __future__ import annotations

from typing import NamedTuple

import pytest

from conesim.planner import MidlineConfig, SpeedProfileConfig, settings
from conesim.planner.settings import from_fields


class Pair(NamedTuple):
    """A group of a float and a count."""

    width: float
    count: int


class Source:
    """Attributes of the group's names, as ints (a value read from YAML)."""

    width = 3
    count = 2


def test_from_fields_converts_each_field_to_its_type() -> None:
    """3 read as a width becomes 3.0; a count stays an int; a computed field wins."""
    pair = from_fields(Pair, Source())
    assert pair == Pair(3.0, 2)
    assert type(pair.width) is float and type(pair.count) is int
    assert from_fields(Pair, Source(), width=0.5) == Pair(0.5, 2)
    with pytest.raises(AttributeError, match="count"):
        from_fields(Pair, object(), width=1.0)


def test_midline_groups_carry_the_config_s_values() -> None:
    """The defaults by name: view -3 m to 30 m, 0.5-4 m off the path, 2 samples,
    nominal 3 m; partners within 4 m; bridges 2.5-6 m wide, 7 m long, shortest;
    the chain's 7 m steps."""
    config = MidlineConfig()
    view = config.view_settings
    assert isinstance(view, settings.ViewSettings)
    assert (view.min_x, view.max_range, view.min_boundary_offset) == (-3.0, 30.0, 0.5)
    assert (view.min_width_samples, view.nominal_track_width) == (2, 3.0)
    assert view.boundary_tolerance == 0.75
    assert config.partner_settings == settings.PartnerSettings(
        partner_radius=4.0, partner_offset_tolerance=0.5
    )
    assert config.bridge_settings == settings.BridgeSettings(
        2.5, 6.0, 7.0, 6.0, 0.75, shortest=True
    )
    assert not MidlineConfig(bridge_selection="all").bridge_settings.shortest
    ordering = config.ordering_settings
    assert isinstance(ordering, settings.OrderingSettings)
    assert (ordering.max_step, ordering.min_midpoint_spacing) == (7.0, 1.0)
    assert config.view_settings is view  # built once


def test_speed_profile_groups_carry_the_config_s_values() -> None:
    """The curvature floor a_lat_max / v_max^2 = 12 / 625 = 0.0192 1/m; the passes
    brake unless asked not to."""
    config = SpeedProfileConfig()
    limits = config.limit_settings
    assert isinstance(limits, settings.LimitSettings)
    assert limits.curvature_floor == pytest.approx(0.0192, rel=1e-12)
    assert (limits.curvature_window, limits.v_max, limits.lateral_jerk_max) == (2.0, 25.0, 60.0)
    passes = config.pass_settings
    assert passes == settings.PassSettings(
        True, 3.0, 8.0, 12.0, 0.0122, horizon_stop=True, brake=True
    )
    assert type(passes.friction_ellipse) is bool
