"""Tests for envs.scenario_file: the YAML format, overrides, validation, show."""

from __future__ import annotations

import dataclasses
import itertools
import math
from pathlib import Path
from typing import Any

import pytest

from conesim.envs.dataclass_io import FieldError
from conesim.envs.scenario import Scenario
from conesim.envs.scenario_file import (
    Override,
    load_scenario,
    scenario_from_mapping,
    scenario_to_mapping,
    scenario_yaml,
)
from conesim.envs.yaml_io import parse_yaml
from conesim.localization.ekf import PROFILES as EKF_PROFILES
from conesim.localization.ekf import EkfConfig
from conesim.planner import AutopilotConfig
from conesim.sim.sensors import ConeFaults, Faults, GpsFaults, get_profile, override
from conesim.sim.vehicle_params import VehicleParams
from conesim.tracks import GeneratedTrack, load_track
from conesim.tracks.survey import ConeSurvey, PathSurvey

EXAMPLE = Path(__file__).resolve().parents[2] / "scenarios" / "example.yaml"


def write(tmp_path: Path, text: str, name: str = "s.yaml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def test_the_example_file_loads_as_documented() -> None:
    """scenarios/example.yaml: autocross, seed 7, rtk with 20 m cones, five faults,
    the matched (rtk) tuning, colour classification at 18 m/s, 200 kg."""
    s = load_scenario(EXAMPLE)
    assert (s.track, s.laps, s.seed, s.localization) == ("autocross", 1, 7, "fused")
    assert s.sensors == override(get_profile("rtk"), {"cones.max_range": 20.0})
    assert s.faults.active == (
        "gps.dropouts", "gps.multipath_rate", "gps.multipath_size", "imu.gyro_bias",
        "cones.detection_probability", "cones.false_positives_per_scan",
        "cones.colour_swap_probability",
    )  # fmt: skip
    assert s.faults.gps.dropouts == ((12.0, 14.0),)
    assert s.ekf is None and s.ekf_tuning_name == "rtk"
    assert s.autopilot is not None and s.autopilot.classifier.mode == "colour"
    assert s.autopilot.speed_profile.v_max == 18.0
    assert s.autopilot.speed_profile.a_lat_max == AutopilotConfig().speed_profile.a_lat_max
    assert s.vehicle == VehicleParams(mass=200.0)


def test_an_empty_file_is_the_defaults(tmp_path: Path) -> None:
    """Every key is optional: an empty file and no file are Scenario()."""
    assert load_scenario(write(tmp_path, "")) == Scenario() == load_scenario()
    assert load_scenario(write(tmp_path, "# nothing\n", "c.yaml")) == Scenario()


def test_groups_by_name_and_presets() -> None:
    """'sensors: consumer', 'ekf: consumer', 'autopilot: cautious' are their names;
    a preset or a tuning with fields changes only those fields."""
    s = scenario_from_mapping({"sensors": "consumer", "ekf": "consumer", "autopilot": "cautious"})
    assert s.sensors == get_profile("consumer") and s.ekf is None and s.ekf_tuning == "consumer"
    assert s.autopilot == AutopilotConfig.cautious()
    s = scenario_from_mapping(
        {"localization": "raw", "autopilot": {"pure_pursuit": {"lookahead_gain": 0.5}},
         "ekf": {"tuning": "consumer", "gate_probability": 0.99}},
    )  # fmt: skip
    assert s.autopilot == dataclasses.replace(
        AutopilotConfig.cautious(),
        pure_pursuit=dataclasses.replace(AutopilotConfig().pure_pursuit, lookahead_gain=0.5),
    )  # auto: cautious with the raw pose, then the change
    assert s.ekf == dataclasses.replace(EKF_PROFILES["consumer"], gate_probability=0.99)


def test_a_renamed_profile_keeps_its_base_tuning() -> None:
    """consumer sensors named 'm8_car': consumer's tuning, settled at load (the name
    alone no longer says which)."""
    s = scenario_from_mapping({"sensors": {"profile": "consumer", "name": "m8_car"}})
    assert s.sensors.name == "m8_car" and s.ekf == EKF_PROFILES["consumer"]
    assert s.ekf_tuning == "consumer"


def test_the_order_of_keys_does_not_matter() -> None:
    """Every order of the top-level keys and of the faults gives the same scenario."""
    data: dict[str, Any] = {
        "track": "autocross",
        "faults": {"cones": {"detection_probability": 0.7, "noise_scale": 2.0},
                   "gps": {"multipath_rate": 0.1, "dropouts": [[1, 2]]}},
        "sensors": {"cones": {"max_range": 20}, "profile": "consumer"},
        "localization": "raw",
    }  # fmt: skip
    first = scenario_from_mapping(data)
    for order in itertools.permutations(data):
        assert scenario_from_mapping({k: data[k] for k in order}) == first
    cones = dict(reversed(data["faults"]["cones"].items()))
    flipped = {**data, "faults": {"gps": data["faults"]["gps"], "cones": cones}}
    assert scenario_from_mapping(flipped) == first


def test_overrides_are_edits_of_the_file(tmp_path: Path) -> None:
    """A dotted override changes one key, making mappings on the way, over a group's
    name too; later overrides win."""
    path = write(tmp_path, "sensors: consumer\nlaps: 2\n")
    s = load_scenario(path, {"sensors.cones.max_range": 25, "laps": 3,
                             "faults.cones.detection_probability": 0.7})  # fmt: skip
    assert s.sensors.name == "consumer" and s.sensors.cones.max_range == 25.0
    assert s.laps == 3 and s.faults.cones.detection_probability == 0.7
    s = load_scenario(path, [Override("seed", 1), Override("seed", 2)])
    assert s.seed == 2


def test_a_generated_track_over_a_named_one_replaces_it(tmp_path: Path) -> None:
    """``track.generate.seed`` over ``track: autocross``: the generated track, its
    other keys at their defaults; over a generated track, one key changes."""
    named = load_scenario(write(tmp_path, "track: autocross\n"), {"track.generate.seed": 3})
    generated = load_scenario(None, {"track": {"generate": {"seed": 3}}})
    assert named.track == generated.track and isinstance(named.track, GeneratedTrack)
    assert named.track.seed == 3
    path = write(tmp_path, "track: {generate: {seed: 1, size: large}}\n")
    changed = load_scenario(path, {"track.generate.seed": 4}).track
    assert isinstance(changed, GeneratedTrack) and (changed.seed, changed.spec.size) == (4, "large")


def test_a_track_file_is_relative_to_the_scenario(tmp_path: Path, monkeypatch: Any) -> None:
    """'track: t.yaml' next to the scenario is that file, as an absolute path."""
    (tmp_path / "sub").mkdir()
    text = Path(load_track("acceleration").source or "").read_text()
    (tmp_path / "sub" / "t.yaml").write_text(text.replace("global_path:", "# global_path:"))
    path = write(tmp_path / "sub", "track: t.yaml\n")
    monkeypatch.chdir(tmp_path)
    assert load_scenario(path).track == str(tmp_path / "sub" / "t.yaml")
    assert load_scenario(None, {"track": "sub/t.yaml"}).track == str(tmp_path / "sub" / "t.yaml")
    assert load_scenario(path, {"track": "autocross"}).track == "autocross"


SCENARIOS = [
    Scenario(),
    load_scenario(EXAMPLE),
    Scenario(localization="raw", sensors=get_profile("ideal"), laps=3, time_limit=12.5),
    Scenario(
        sensors=dataclasses.replace(override(get_profile("consumer"), {"gps.rate": 8.0}),
                                    name="lidar_car"),
        ekf=EkfConfig(gate_probability=0.95),
        autopilot=AutopilotConfig.cautious(),
        faults=Faults(gps=GpsFaults(bias_drift=(0.01, -0.02), bias_drift_start=3.0),
                      cones=ConeFaults(extra_latency=0.05)),
        vehicle=VehicleParams(mu=0.8),
    ),
]  # fmt: skip


@pytest.mark.parametrize("scenario", SCENARIOS, ids=["defaults", "example", "raw", "in-code"])
def test_show_reads_back_as_the_resolved_scenario(scenario: Scenario) -> None:
    """show's YAML, read again, is the same scenario, every value exact: a run can be
    made again from it alone. Shown again, it is the same text."""
    text = scenario_yaml(scenario)
    again = scenario_from_mapping(parse_yaml(text, "show")[0])
    assert again == scenario.resolved()
    assert scenario_yaml(again) == text


def test_show_fills_in_every_default_and_names_the_tuning() -> None:
    """Every field of every part is there; the EKF tuning is the one taken."""
    data = scenario_to_mapping(Scenario(sensors=get_profile("consumer")))
    assert data["ekf"]["tuning"] == "consumer" and data["ekf"]["gps_bias_sigma"] == 2.0
    assert data["autopilot"]["preset"] == "default"
    assert "origin" not in data["ekf"] and "sensor_frame" not in data["autopilot"]
    assert data["sensors"]["cones"]["confusion"][3] == [0.0, 0.0, 0.0, 1.0]
    assert data["faults"]["cones"]["detection_probability"] == 1.0
    assert len(data["vehicle"]) == len(dataclasses.fields(VehicleParams))
    ideal = scenario_to_mapping(Scenario(sensors=get_profile("ideal")))
    assert ideal["sensors"]["cones"]["colour_range"] == math.inf
    assert "colour_range: .inf" in scenario_yaml(Scenario(sensors=get_profile("ideal")))


BAD = [
    # unknown keys: the key, its path and the allowed keys
    ("lap: 2\n", "s.yaml:1: lap: unknown key 'lap'; allowed keys: conesim_scenario, track, laps,"),
    ("sensors:\n  cones:\n    range: 20\n",
     "s.yaml:3: sensors.cones.range: unknown key 'range'; allowed keys: rate, latency,"),
    ("sensors:\n  profil: rtk\n",
     "s.yaml:2: sensors.profil: unknown key 'profil'; allowed keys: profile, name, gps,"),
    ("faults:\n  cones:\n    misses: 0.3\n",
     "s.yaml:3: faults.cones.misses: unknown key 'misses'; allowed keys: detection_probability,"),
    ("ekf:\n  origin: 1\n", "s.yaml:2: ekf.origin: unknown key 'origin'; allowed keys: tuning,"),
    ("autopilot:\n  speed_profile:\n    vmax: 10\n",
     "s.yaml:3: autopilot.speed_profile.vmax: unknown key 'vmax'; allowed keys: a_lat_max,"),
    # out of range: the configs' own messages, at the field
    ("laps: 0\n", "s.yaml:1: laps: Scenario.laps = 0 is out of range: allowed [1, 100]"),
    ("sensors:\n  cones:\n    max_range: -1\n",
     "s.yaml:3: sensors.cones.max_range: ConeDetectorConfig.max_range = -1.0 is out of range: "
     "allowed (0, inf) [m]"),
    ("faults:\n  cones:\n    detection_probability: 1.5\n",
     "s.yaml:3: faults.cones.detection_probability: ConeFaults.detection_probability = 1.5 is "
     "out of range: allowed [0, 1]"),
    ("faults:\n  gps:\n    dropouts: [[12, 10]]\n",
     "s.yaml:3: faults.gps.dropouts: GpsFaults.dropouts[0] = (12.0, 10.0) is out of range: "
     "allowed [start, end] [s] with 0 <= start < end"),
    ("ekf:\n  gate_probability: 1.0\n",
     "s.yaml:2: ekf.gate_probability: EkfConfig.gate_probability = 1.0 is out of range: "
     "allowed (0, 1)"),
    ("vehicle:\n  mass: 0\n",
     "s.yaml:2: vehicle.mass: VehicleParams.mass must be in (0, inf) [kg], got 0.0"),
    ("autopilot:\n  classifier:\n    window_back: -1\n",
     "s.yaml:3: autopilot.classifier.window_back: ClassifierConfig.window_back = -1.0 is out "
     "of range"),
    ("control_rate: 30\n", "s.yaml:1: control_rate: Scenario: physics_rate (200.0 Hz) must be "
     "a whole multiple of control_rate (30.0 Hz)"),
    ("time_limit: -5\n",
     "s.yaml:1: time_limit: EpisodeRules.time_limit must be finite and > 0 [s]"),
    # wrong types: the expected type
    ("laps: two\n", "s.yaml:1: laps: expected an integer, got 'two' (text)"),
    ("laps: 1.5\n", "s.yaml:1: laps: expected an integer, got 1.5 (a number)"),
    ("seed: true\n", "s.yaml:1: seed: expected an integer, got True (a boolean)"),
    ("end_on_stuck: 1\n", "s.yaml:1: end_on_stuck: expected true or false, got 1 (a number)"),
    ("time_limit: soon\n", "s.yaml:1: time_limit: expected a number, got 'soon' (text), or null"),
    ("track: 3\n",
     "s.yaml:1: track: expected a track name, a file or {generate: {seed: S, ...}}, got 3"),
    ("localization: gps\n",
     "s.yaml:1: localization: expected one of 'fused', 'raw', 'truth', 'cones', 'slam', got 'gps'"),
    ("sensors:\n  cones:\n    occlusion: maybe\n",
     "s.yaml:3: sensors.cones.occlusion: expected true or false, got 'maybe' (text)"),
    ("sensors:\n  gps:\n    fix_status: RTK\n",
     "s.yaml:3: sensors.gps.fix_status: expected one of NO_FIX, FIX, SBAS_FIX, GBAS_FIX"),
    ("faults:\n  gps:\n    bias_drift: 0.1\n",
     "s.yaml:3: faults.gps.bias_drift: expected a list of 2, got 0.1 (a number)"),
    ("faults:\n  gps:\n    dropouts: [[1, 2, 3]]\n",
     "s.yaml:3: faults.gps.dropouts[0]: expected a list of 2 items, got 3"),
    ("sensors:\n  cones: 20\n",
     "s.yaml:2: sensors.cones: expected a mapping of ConeDetectorConfig fields, got 20"),
    ("vehicle: heavy\n", "s.yaml:1: vehicle: expected a mapping of VehicleParams fields"),
    ("- 1\n- 2\n", "s.yaml: expected a mapping of scenario keys"),
    # the groups' names, the format's version, the file itself
    ("sensors: gnss\n", "s.yaml:1: sensors.profile: unknown profile 'gnss'; allowed: ideal, rtk,"),
    ("ekf: fast\n",
     "s.yaml:1: ekf.tuning: expected one of 'auto', 'ideal', 'rtk', 'consumer', 'consumer_white',"
     " 'custom', got 'fast'"),
    ("autopilot: fast\n",
     "s.yaml:1: autopilot.preset: expected one of 'auto', 'default', 'cautious', got 'fast'"),
    ("sensors: [rtk]\n", "s.yaml:1: sensors: expected a mapping or a profile name, got ['rtk']"),
    ("conesim_scenario: 2\n",
     "s.yaml:1: conesim_scenario: unknown format version 2; allowed: 1"),
    ("laps: 1\nlaps: 2\n", "s.yaml:2: laps: duplicate key"),
    ("laps: [1\n", "s.yaml:2: not valid YAML:"),
]  # fmt: skip


@pytest.mark.parametrize(("text", "message"), BAD)
def test_every_validation_error_is_one_located_line(
    text: str, message: str, tmp_path: Path, monkeypatch: Any
) -> None:
    """Unknown keys name the key, path and allowed keys; a value out of range names
    the range; a wrong type the expected type: one line, with the file and line."""
    monkeypatch.chdir(tmp_path)
    write(tmp_path, text)
    with pytest.raises(FieldError) as info:
        load_scenario("s.yaml")
    assert str(info.value).startswith(message), str(info.value)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize(
    ("override", "message"),
    [
        (Override("sensors.cones.foo", 1, "--set sensors.cones.foo=1"),
         "--set sensors.cones.foo=1: sensors.cones.foo: unknown key 'foo'; allowed keys: rate,"),
        (Override("laps.total", 3, "--set laps.total=3"),
         "--set laps.total=3: laps: is 1, not a mapping"),
        (Override("faults..cones", 1), "override faults..cones: bad key 'faults..cones'"),
        (Override("laps", "x", "--laps x"), "--laps x: laps: expected an integer, got 'x'"),
    ],
)  # fmt: skip
def test_an_override_error_names_the_override(
    override: Override, message: str, tmp_path: Path
) -> None:
    """A bad value from an override names the override, not the file's line."""
    path = write(tmp_path, "laps: 1\nsensors:\n  cones:\n    max_range: 20\n")
    with pytest.raises(FieldError) as info:
        load_scenario(path, [override])
    assert str(info.value).startswith(message), str(info.value)


def test_a_key_made_a_mapping_by_an_override_is_blamed_on_it() -> None:
    """``--set seed.x=1`` with no seed given makes ``seed`` a mapping; the error
    names the override, not a file or nothing."""
    with pytest.raises(FieldError) as info:
        load_scenario(None, [Override("seed.x", 1, "--set seed.x=1")])
    assert str(info.value).startswith("--set seed.x=1: seed: expected an integer, got {'x': 1}")


def test_the_readmes_example_loads() -> None:
    """The YAML block of the README's Scenarios section is a valid scenario."""
    readme = (EXAMPLE.parents[1] / "README.md").read_text()
    section = readme[readme.index("### Scenarios") :]
    block = section[
        section.index("```yaml\n") + 8 : section.index("```\n", section.index("```yaml"))
    ]
    s = scenario_from_mapping(parse_yaml(block, "README.md")[0])
    assert s.track == "autocross" and s.faults.gps.dropouts == ((12.0, 14.0),)
    assert s.autopilot is not None and s.autopilot.classifier.mode == "colour"


def test_global_path_survey_is_read_and_checked() -> None:
    """``global_path: {noise, bias, seed}`` becomes a PathSurvey; a bad value is one line."""
    s = scenario_from_mapping({"global_path": {"noise": 0.2, "bias": 0.3, "seed": 4}})
    assert s.global_path == PathSurvey(0.2, 0.3, 4)
    assert scenario_from_mapping({}).global_path.exact
    with pytest.raises(FieldError, match=r"global_path.noise: PathSurvey.noise = -1.0"):
        scenario_from_mapping({"global_path": {"noise": -1.0}})
    with pytest.raises(FieldError, match="unknown key 'nois'; allowed keys: noise, bias, seed"):
        scenario_from_mapping({"global_path": {"nois": 0.1}})


def test_cone_map_survey_is_read_checked_and_shown() -> None:
    """``cone_map: {noise, bias, seed}`` becomes a ConeSurvey (default 3 cm, 2 cm); ``show``
    writes it and reads back the same; a bad value is one line."""
    s = scenario_from_mapping({"localization": "cones", "cone_map": {"noise": 0.1, "seed": 2}})
    assert s.localization == "cones" and s.cone_map == ConeSurvey(0.1, 0.02, 2)
    assert scenario_from_mapping({}).cone_map == ConeSurvey(0.03, 0.02, 0)
    shown = scenario_to_mapping(s)
    assert shown["localization"] == "cones"
    assert shown["cone_map"] == {"noise": 0.1, "bias": 0.02, "seed": 2}
    assert scenario_from_mapping(shown).cone_map == s.cone_map
    with pytest.raises(FieldError, match=r"cone_map.bias: ConeSurvey.bias = -1.0"):
        scenario_from_mapping({"cone_map": {"bias": -1.0}})
