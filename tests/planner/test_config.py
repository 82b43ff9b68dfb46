"""Planner settings: construction from mappings, unknown keys, ranges."""

from __future__ import annotations

import pytest

from conesim import planner


def test_unknown_key_lists_the_allowed_keys() -> None:
    """An unknown key raises, naming itself and every allowed key."""
    with pytest.raises(ValueError, match="unknown keys \\['a_lat'\\]") as info:
        planner.SpeedProfileConfig.from_dict({"a_lat": 5.0})
    for key in ("a_lat_max", "a_drive", "a_brake", "v_max", "horizon_stop"):
        assert key in str(info.value)


def test_nested_mapping_builds_nested_settings() -> None:
    """AutopilotConfig.from_dict turns nested mappings into the stage settings."""
    config = planner.AutopilotConfig.from_dict(
        {
            "speed_window": 0.2,
            "pure_pursuit": {"wheelbase": 2.0},
            "classifier": {"mode": "colour"},
        }
    )
    assert config.speed_window == 0.2
    assert config.pure_pursuit == planner.PurePursuitConfig(wheelbase=2.0)
    assert config.classifier.mode == "colour"
    assert config.midline == planner.MidlineConfig()


def test_a_nested_mapping_updates_the_field_s_own_default() -> None:
    """The racing line's limits differ from SpeedProfileConfig's defaults: a
    mapping that changes one of them keeps the others (13 + 0.0132 v^2, the
    drive ellipse 1.2 times as wide), not SpeedProfileConfig()'s."""
    config = planner.AutopilotConfig.from_dict({"racing_speed_profile": {"a_lat_max": 14.0}})
    racing = config.racing_speed_profile
    assert (racing.a_lat_max, racing.a_lat_aero, racing.drive_lateral_share) == (14.0, 0.0132, 1.2)
    assert config.speed_profile == planner.SpeedProfileConfig()
    assert planner.AutopilotConfig().racing_speed_profile.a_lat_max == 13.0


def test_unknown_nested_key_raises() -> None:
    """Unknown keys are caught at every level."""
    with pytest.raises(ValueError, match="MidlineConfig: unknown keys \\['spline'\\]"):
        planner.AutopilotConfig.from_dict({"midline": {"spline": 3}})


@pytest.mark.parametrize(
    ("cls", "values"),
    [
        (planner.SpeedProfileConfig, {"a_lat_max": 0.0}),
        (planner.SpeedProfileConfig, {"v_max": float("nan")}),
        (planner.MidlineConfig, {"max_track_width": 2.0}),  # below min_track_width
        (planner.MidlineConfig, {"spacing": -0.5}),
        (planner.MidlineConfig, {"bridge_selection": "some"}),
        (planner.PurePursuitConfig, {"lookahead_max": 1.0}),  # below lookahead_min
        (planner.ClassifierConfig, {"mode": "magic"}),
        (planner.ClassifierConfig, {"left_colours": ("blue",), "right_colours": ("blue",)}),
        (planner.ClassifierConfig, {"left_colours": "blue"}),  # a string, not a tuple of colours
        (planner.ClassifierConfig, {"right_colours": ("Yellow",)}),  # not a CONE_COLOURS label
        (planner.AutopilotConfig, {"speed_window": 0.0}),
        (planner.AutopilotConfig, {"speed_source": "map"}),
        (planner.SpeedControlConfig, {"integral_band": -1.0}),
        (planner.SpeedControlConfig, {"lateral_grip": 0.0}),
        (planner.SpeedControlConfig, {"ellipse_floor": 1.5}),
        (planner.SpeedControlConfig, {"grip_aero": -0.01}),
        (planner.SpeedProfileConfig, {"a_lat_aero": -0.01}),
        (planner.SpeedProfileConfig, {"lateral_jerk_max": 0.0}),
        (planner.PurePursuitConfig, {"lookahead_radius_ratio": 0.0}),
        (planner.PurePursuitConfig, {"slip_stiffness": 0.0}),
    ],
)
def test_out_of_range_values_raise(cls: type, values: dict[str, object]) -> None:
    """Values out of range raise ValueError when the settings are built."""
    with pytest.raises(ValueError):
        cls.from_dict(values)


def test_colour_lists_from_a_file_are_tuples() -> None:
    """left_colours given as a list (YAML) is kept as the tuple of its colours."""
    config = planner.ClassifierConfig.from_dict(
        {"mode": "colour", "left_colours": ["blue", "orange"]}
    )
    assert config.left_colours == ("blue", "orange")
