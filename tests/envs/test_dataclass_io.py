"""Tests for envs.dataclass_io: dataclasses from plain data, errors by path, and back."""

from __future__ import annotations

import dataclasses
import enum
import math
import pickle
from dataclasses import dataclass, field
from typing import Literal

import pytest

from conesim.core.messages import NavSatStatus
from conesim.envs.dataclass_io import FieldError, build, convert, dotted, plain
from conesim.planner import AutopilotConfig
from conesim.sim.sensors import get_profile
from conesim.sim.sensors.gps import GpsConfig
from conesim.sim.sensors.profiles import SensorProfile
from conesim.sim.vehicle_params import VehicleParams


class Mode(enum.StrEnum):
    A = "a"
    B = "b"


@dataclass(frozen=True)
class Inner:
    """A nested config that checks its own range."""

    gain: float = 1.0  # [-]
    window: tuple[float, float] = (0.0, 1.0)  # [s]

    def __post_init__(self) -> None:
        if not self.gain >= 0.0:
            raise ValueError(f"Inner.gain = {self.gain!r} is out of range: allowed >= 0")


@dataclass(frozen=True)
class Outer:
    """A config with one field of every kind the helper converts."""

    count: int = 1
    rate: float = 2.0  # [Hz]
    on: bool = True
    name: str = "x"
    choice: Literal["geometric", "colour"] = "geometric"
    mode: Mode = Mode.A
    status: NavSatStatus = NavSatStatus.FIX
    limit: float | None = None  # [s]
    names: tuple[str, ...] = ()
    inner: Inner = field(default_factory=Inner)


def test_every_kind_of_field_converts() -> None:
    """Numbers, booleans, text, choices, enums by name (text enums by value), null,
    lists as tuples and nested mappings."""
    got = build(
        Outer,
        {"count": 3, "rate": 5, "on": False, "name": "y", "choice": "colour", "mode": "b",
         "status": "GBAS_FIX", "limit": 30, "names": ["blue", "yellow"],
         "inner": {"gain": 2, "window": [1, 2.5]}},
    )  # fmt: skip
    assert got == Outer(3, 5.0, False, "y", "colour", Mode.B, NavSatStatus.GBAS_FIX, 30.0,
                        ("blue", "yellow"), Inner(2.0, (1.0, 2.5)))  # fmt: skip
    assert type(got.rate) is float and type(got.inner.gain) is float  # 5 -> 5.0: bit for bit


def test_a_base_keeps_what_the_mapping_leaves_out_nested_too() -> None:
    """Given a base, only the keys given change, also inside nested configs."""
    base = Outer(count=7, inner=Inner(gain=3.0, window=(2.0, 3.0)))
    got = build(Outer, {"inner": {"gain": 4.0}}, base=base)
    assert got == Outer(count=7, inner=Inner(gain=4.0, window=(2.0, 3.0)))


@pytest.mark.parametrize(
    ("data", "message"),
    [
        ({"cuont": 1}, "cuont: unknown key 'cuont'; allowed keys: count, rate, on, name,"),
        ({"count": 1.5}, "count: expected an integer, got 1.5 (a number)"),
        ({"count": True}, "count: expected an integer, got True (a boolean)"),
        ({"rate": "fast"}, "rate: expected a number, got 'fast' (text)"),
        ({"rate": False}, "rate: expected a number, got False (a boolean)"),
        ({"on": 1}, "on: expected true or false, got 1 (a number)"),
        ({"name": 3}, "name: expected text, got 3 (a number)"),
        ({"choice": "color"}, "choice: expected one of 'geometric', 'colour', got 'color'"),
        ({"mode": "A"}, "mode: expected one of a, b, got 'A'"),
        ({"status": 2}, "status: expected one of NO_FIX, FIX, SBAS_FIX, GBAS_FIX, got 2"),
        ({"limit": "30 s"}, "limit: expected a number, got '30 s' (text), or null"),
        ({"names": "blue"}, "names: expected a list, got 'blue' (text)"),
        ({"names": ["blue", 1]}, "names[1]: expected text, got 1 (a number)"),
        ({"inner": {"window": [1.0]}}, "inner.window: expected a list of 2 items, got 1"),
        ({"inner": 5}, "inner: expected a mapping of Inner fields, got 5 (a number)"),
        ({"inner": {"gain": -1.0}}, "inner.gain: Inner.gain = -1.0 is out of range: allowed >= 0"),
    ],
)
def test_each_problem_is_one_error_naming_the_path(data: dict[str, object], message: str) -> None:
    """Unknown keys list the allowed ones, wrong types name the expected type, a
    config's own range check keeps its message, at the field it names."""
    with pytest.raises(FieldError) as info:
        build(Outer, data)
    assert str(info.value).startswith(message), str(info.value)
    assert "\n" not in str(info.value)


def test_hidden_fields_cannot_be_set() -> None:
    """A field kept from the base (the frames of the autopilot) is an unknown key."""
    hidden = {AutopilotConfig: frozenset({"reference_frame", "sensor_frame"})}
    with pytest.raises(FieldError, match="unknown key 'sensor_frame'; allowed keys: classifier"):
        build(AutopilotConfig, {"sensor_frame": "x"}, hidden=hidden)
    assert "sensor_frame" not in plain(AutopilotConfig(), hidden)


def test_the_error_says_where_and_survives_pickling() -> None:
    """A located error reads 'where: path: reason'; it pickles (worker processes)."""
    error = FieldError(("sensors", "gps", "dropouts", 0), "bad", None).located("s.yaml:4")
    assert str(error) == "s.yaml:4: sensors.gps.dropouts[0]: bad"
    again = pickle.loads(pickle.dumps(error))
    assert (again.path, again.reason, again.where) == (error.path, "bad", "s.yaml:4")
    assert dotted(()) == "" and str(FieldError((), "empty file", "s.yaml")) == "s.yaml: empty file"


@pytest.mark.parametrize(
    "value",
    [
        get_profile("consumer"),
        get_profile("ideal"),  # colour_range inf
        VehicleParams(mass=200.0),
        AutopilotConfig.cautious(),
        GpsConfig(dropouts=((1.0, 2.0),), fix_status=NavSatStatus.GBAS_FIX, reported_sigma=0.1),
    ],
)
def test_plain_and_build_are_inverses(value: object) -> None:
    """plain() lists every field; build() of it is an equal object, its floats exact."""
    data = plain(value)
    again = build(type(value), data)
    assert again == value
    assert set(data) == {f.name for f in dataclasses.fields(value)}  # type: ignore[arg-type]


def test_plain_data_is_json_and_yaml_ready() -> None:
    """Tuples become lists, enums names; infinity stays a float."""
    data = plain(get_profile("ideal"))
    assert data["gps"]["fix_status"] == "FIX"
    assert data["cones"]["confusion"][0] == [1.0, 0.0, 0.0, 0.0]
    assert data["cones"]["colour_range"] == math.inf
    assert isinstance(build(SensorProfile, data).cones.confusion, tuple)


def test_convert_leaves_an_object_of_the_type_as_it_is() -> None:
    """An Inner passed where an Inner is meant is kept (code may mix objects in)."""
    inner = Inner(gain=2.0)
    assert convert(inner, Inner) is inner
