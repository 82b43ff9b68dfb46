"""Scenario files: the YAML form of a ``Scenario``, dotted overrides, and ``show``.

The format (version 1; every key optional, the defaults are ``conesim run``'s)::

    conesim_scenario: 1
    track: trackdrive          # a shipped track, or a file (relative to this file),
                               # or {generate: {seed: 3, size: small, ...}} (TrackSpec)
    laps: 1
    seed: 0
    time_limit: null           # [s]; null: 60 s per lap + 30 s
    end_on_off_track: true
    end_on_stuck: true
    control_rate: 50.0         # [Hz]
    physics_rate: 200.0        # [Hz], a multiple of control_rate
    localization: fused        # fused | raw | truth | cones | slam
    sensors:                   # or just a profile's name: "sensors: consumer"
      profile: rtk             # the shipped profile the fields below change
      cones: {max_range: 20.0} # any field of GpsConfig, HeadingConfig, ... by section
    faults:                    # sim.sensors.faults, per sensor
      cones: {detection_probability: 0.7}
      gps: {dropouts: [[10.0, 12.0]]}
    ekf:                       # or just a tuning's name
      tuning: auto             # auto (matched to the sensors) | ideal | rtk | consumer | ...
      gate_probability: 0.99   # any EkfConfig field
    autopilot:                 # or just a preset's name
      preset: auto             # auto (cautious with raw) | default | cautious
      classifier: {mode: colour}
    vehicle: {mass: 200.0}     # any VehicleParams field
    global_path: {noise: 0.2, bias: 0.3, seed: 1}   # the surveyed path's error [m]
    cone_map: {noise: 0.03, bias: 0.02, seed: 0}    # the cone map's error (cones mode) [m]
    slam: {confirm_scans: 3, prune_misses: 5}       # building the map (slam mode)

Overrides (``--set sensors.cones.max_range=20``, or ``load_scenario(path,
{"laps": 3})``) change the file's mapping before it is checked, so an
override is exactly an edit of the file: a sweep (a base scenario and one
dotted key varied) is a list of overrides. Each problem is one
``FieldError`` naming the key's path, its file and line (or the override
that set it) and the allowed keys, range or type.

``scenario_to_mapping`` writes the resolved scenario with every field
filled in (``conesim scenario show``): read back, it is the same scenario,
so a run can be reproduced from it alone. A track file is written as an
absolute path so that the output runs from anywhere.
"""

from __future__ import annotations

import copy
import dataclasses
import os
import re
import typing
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

from conesim.envs.dataclass_io import FieldError, Hidden, Path, build, convert, plain, settable
from conesim.envs.ekf_tuning import matched_ekf
from conesim.envs.scenario import AutopilotPreset, EkfTuning, Scenario
from conesim.envs.yaml_io import Lines, dump_yaml, read_yaml
from conesim.localization.ekf import EkfConfig, for_profile
from conesim.localization.slam import SlamConfig
from conesim.planner import AutopilotConfig
from conesim.planner.autopilot import default_config
from conesim.sim.sensors import DEFAULT_PROFILE, PROFILES, Faults, SensorProfile, get_profile
from conesim.sim.vehicle_params import VehicleParams
from conesim.tracks import GeneratedTrack, TrackSpec, shipped_tracks
from conesim.tracks.survey import ConeSurvey, PathSurvey

FORMAT_KEY = "conesim_scenario"
FORMAT_VERSION = 1
SCALARS = (
    "track", "laps", "seed", "time_limit", "end_on_off_track", "end_on_stuck",
    "control_rate", "physics_rate", "localization",
)  # fmt: skip
"""The top-level keys that are plain values, in the order ``show`` writes them."""
GROUPS = ("sensors", "faults", "ekf", "autopilot", "vehicle", "global_path", "cone_map", "slam")
TOP_KEYS = (FORMAT_KEY, *SCALARS, *GROUPS)
SHORTHAND = {"sensors": "profile", "ekf": "tuning", "autopilot": "preset"}
"""A group given as a plain name means this key of it (``sensors: consumer``)."""
HIDDEN: Hidden = {
    # the frames and the origin are the world's, not settings of a run
    EkfConfig: frozenset({"origin", "reference_frame", "antenna_frame"}),
    AutopilotConfig: frozenset({"reference_frame", "sensor_frame"}),
}


@dataclass(frozen=True)
class Override:
    """One dotted change of a scenario's mapping.

    Attributes:
        key: the dotted path, e.g. ``sensors.cones.detection_probability_at_zero``.
        value: its new value (plain data: a number, text, list, mapping, null).
        origin: how the user gave it, for errors (``--set laps=3``); default
            ``override KEY``.
    """

    key: str
    value: Any
    origin: str = ""

    @property
    def label(self) -> str:
        """Where an error in this value came from."""
        return self.origin or f"override {self.key}"


class _Places:
    """Where each part of the mapping came from: ``file:line`` or an override."""

    def __init__(self, source: str | None, lines: Lines) -> None:
        self.source = source
        self.places: dict[Path, str] = {p: f"{source}:{n}" for p, n in lines.items()}

    def overridden(self, path: Path, label: str) -> None:
        for known in [p for p in self.places if p[: len(path)] == path]:
            del self.places[known]
        self.places[path] = label

    def of(self, path: Path) -> str | None:
        """The place of the longest prefix of ``path`` that has one, else of a key
        under it (``--set laps.x=1`` made ``laps`` a mapping), else the file."""
        for n in range(len(path), 0, -1):
            if path[:n] in self.places:
                return self.places[path[:n]]
        below = [place for p, place in self.places.items() if path and p[: len(path)] == path]
        if below:
            return below[-1]
        return self.places.get((), self.source)


def _expand(data: dict[str, Any], key: str, sub: str | None = None) -> None:
    """A group given by name becomes a mapping: ``sensors: consumer`` -> {profile: consumer};
    a track named or in a file gives way to a generated one when ``sub`` (the next key
    being set under ``key``) is ``generate``."""
    value = data.get(key)
    if not isinstance(value, str):
        return
    if key in SHORTHAND:
        data[key] = {SHORTHAND[key]: value}
    elif key == "track" and sub == "generate":
        data[key] = {}


def apply_override(data: dict[str, Any], override: Override) -> None:
    """Set ``override.key`` in ``data`` (in place), making mappings on the way.

    ``track.generate.*`` over a track given by name or file replaces it: the
    run drives the generated track (``--set track.generate.seed=3`` on a
    scenario of ``autocross``, or a sweep's generated tracks over it).

    Raises:
        FieldError: an empty key, or a key under a value that is not a mapping.
    """
    parts = override.key.split(".")
    if not all(parts):
        raise FieldError((), f"bad key {override.key!r}: expected names joined by dots")
    node = data
    for depth, part in enumerate(parts[:-1]):
        if depth == 0:
            _expand(node, part, parts[1])
        child = node.setdefault(part, {})
        if child is None:
            child = node[part] = {}
        if not isinstance(child, dict):
            raise FieldError(tuple(parts[: depth + 1]), f"is {child!r}, not a mapping")
        node = child
    node[parts[-1]] = copy.deepcopy(override.value)


def scenario_from_mapping(
    data: Any,
    overrides: Iterable[Override] = (),
    *,
    source: str | None = None,
    lines: Lines | None = None,
) -> Scenario:
    """The scenario a mapping (a file's, with the overrides applied) describes.

    Args:
        data: the mapping (None: an empty file, all defaults).
        overrides: dotted changes applied first, in order.
        source: the file the mapping came from, for errors.
        lines: each key's line in it (``envs.yaml_io.read_yaml``).

    Raises:
        FieldError: the first problem found, one line, located.
    """
    places = _Places(source, lines or {})
    if data is None:
        data = {}
    if not isinstance(data, Mapping):
        raise FieldError((), "expected a mapping of scenario keys", places.of(()))
    data = copy.deepcopy(dict(data))
    for override in overrides:
        try:
            apply_override(data, override)
        except FieldError as exc:
            raise exc.located(override.label) from None
        places.overridden(tuple(override.key.split(".")), override.label)
    try:
        return _scenario(data)
    except FieldError as exc:
        raise exc.located(places.of(exc.path)) from None


def _scenario(data: dict[str, Any]) -> Scenario:
    """The scenario of a whole mapping (errors not yet located)."""
    for key in data:
        if key not in TOP_KEYS:
            raise FieldError((key,), f"unknown key {key!r}; allowed keys: {', '.join(TOP_KEYS)}")
    version = data.get(FORMAT_KEY, FORMAT_VERSION)
    if version != FORMAT_VERSION or isinstance(version, bool):
        raise FieldError((FORMAT_KEY,), f"unknown format version {version!r}; allowed: 1")
    for key in SHORTHAND:
        _expand(data, key)
    hints = typing.get_type_hints(Scenario)
    values: dict[str, Any] = {
        k: convert(data[k], hints[k], (k,)) for k in SCALARS if k in data and k != "track"
    }
    if "track" in data:
        values["track"] = track_from_data(data["track"])
    localization = values.get("localization", "fused")
    base, sensors = _sensors(data.get("sensors"))
    values["sensors"] = sensors
    if data.get("faults") is not None:
        values["faults"] = build(Faults, data["faults"], path=("faults",))
    values["ekf"], values["ekf_tuning"] = ekf_from_data(data.get("ekf"), base, sensors)
    values["autopilot"] = _autopilot(data.get("autopilot"), localization)
    if data.get("vehicle") is not None:
        values["vehicle"] = build(VehicleParams, data["vehicle"], path=("vehicle",))
    if data.get("global_path") is not None:
        values["global_path"] = build(PathSurvey, data["global_path"], path=("global_path",))
    if data.get("cone_map") is not None:
        values["cone_map"] = build(ConeSurvey, data["cone_map"], path=("cone_map",))
    if data.get("slam") is not None:
        values["slam"] = build(SlamConfig, data["slam"], path=("slam",))
    try:
        return Scenario(**values)
    except ValueError as exc:
        reason = str(exc)
        # at the first key the message names that the mapping sets (else the first named)
        named = [word for word in re.findall(r"\w+", reason) if word in SCALARS]
        given = [word for word in named if word in data]
        path = (given or named)[:1]
        raise FieldError(tuple(path), reason) from None


GENERATE_KEY = "generate"


def track_from_data(value: Any, path: Path = ("track",)) -> str | GeneratedTrack:
    """A scenario's ``track``: a name or file (text), or ``{generate: {seed: S, ...}}``
    with any ``TrackSpec`` field beside the seed (``GeneratedTrack``).

    Raises:
        FieldError: another type, unknown keys, or a setting out of range.
    """
    if isinstance(value, GeneratedTrack):
        return value
    if isinstance(value, str):
        return convert(value, str, path)
    if not isinstance(value, Mapping):
        raise FieldError(
            path, f"expected a track name, a file or {{{GENERATE_KEY}: {{seed: S, ...}}}}, "
            f"got {value!r}",
        )  # fmt: skip
    for key in value:
        if key != GENERATE_KEY:
            raise FieldError((*path, key), f"unknown key {key!r}; allowed keys: {GENERATE_KEY}")
    where = (*path, GENERATE_KEY)
    settings = value.get(GENERATE_KEY)
    if settings is None:
        settings = {}
    if not isinstance(settings, Mapping):
        raise FieldError(where, f"expected a mapping of generator settings, got {settings!r}")
    allowed = ["seed", *settable(TrackSpec)]
    for key in settings:
        if key not in allowed:
            raise FieldError(
                (*where, key), f"unknown key {key!r}; allowed keys: {', '.join(allowed)}"
            )
    seed = convert(settings.get("seed", 0), int, (*where, "seed"))
    spec = build(TrackSpec, {k: v for k, v in settings.items() if k != "seed"}, path=where)
    try:
        return GeneratedTrack(seed, spec)
    except ValueError as exc:
        raise FieldError((*where, "seed"), str(exc)) from None


def track_to_data(track: str | GeneratedTrack) -> Any:
    """``track_from_data``'s inverse: every generator setting written out."""
    if isinstance(track, GeneratedTrack):
        return {GENERATE_KEY: {"seed": track.seed, **plain(track.spec)}}
    return track


def _group(value: Any, name: str, head: str, allowed: list[str]) -> tuple[Any, dict[str, Any]]:
    """A group's head key (profile, tuning, preset) and the rest of its mapping."""
    if value is None:
        return None, {}
    if not isinstance(value, Mapping):
        raise FieldError((name,), f"expected a mapping or a {head} name, got {value!r}")
    for key in value:
        if key not in allowed:
            raise FieldError(
                (name, key), f"unknown key {key!r}; allowed keys: {', '.join(allowed)}"
            )
    rest = {k: v for k, v in value.items() if k != head}
    return value.get(head), rest


def _sensors(value: Any) -> tuple[str, SensorProfile]:
    """The base profile's name and the profile a ``sensors`` mapping makes."""
    allowed = ["profile", *settable(SensorProfile)]
    name, rest = _group(value, "sensors", "profile", allowed)
    name = DEFAULT_PROFILE if name is None else name
    if name not in PROFILES:
        raise FieldError(
            ("sensors", "profile"), f"unknown profile {name!r}; allowed: {', '.join(PROFILES)}"
        )
    return name, build(SensorProfile, rest, base=get_profile(name), path=("sensors",))


def ekf_from_data(
    value: Any, base: str, sensors: SensorProfile
) -> tuple[EkfConfig | None, EkfTuning]:
    """The filter's settings (None: left to follow the sensors) and the tuning's name.

    ``base`` is the shipped profile the sensors started from: a profile
    renamed (``sensors.name``) no longer says by its name which tuning
    matches it, so its tuning is settled here.
    """
    allowed = ["tuning", *settable(EkfConfig, HIDDEN)]
    tuning, rest = _group(value, "ekf", "tuning", allowed)
    tuning = convert("auto" if tuning is None else tuning, EkfTuning, ("ekf", "tuning"))
    if tuning == "auto":
        if not rest and sensors.name == base:
            return None, "auto"
        start, label = matched_ekf(sensors, base), typing.cast(EkfTuning, base)
    else:
        if not rest:
            return None, tuning
        start, label = (EkfConfig() if tuning == "custom" else for_profile(tuning)), tuning
    return build(EkfConfig, rest, base=start, path=("ekf",), hidden=HIDDEN), label


def _autopilot(value: Any, localization: str) -> AutopilotConfig | None:
    """The autopilot's settings; None: the localization's default."""
    allowed = ["preset", *settable(AutopilotConfig, HIDDEN)]
    preset, rest = _group(value, "autopilot", "preset", allowed)
    preset = convert("auto" if preset is None else preset, AutopilotPreset, ("autopilot", "preset"))
    if preset == "auto" and not rest:
        return None
    start = {
        "auto": default_config(localization),
        "default": AutopilotConfig(),
        "cautious": AutopilotConfig.cautious(),
    }[preset]
    return build(AutopilotConfig, rest, base=start, path=("autopilot",), hidden=HIDDEN)


def absolute_track(track: Any, base_dir: str) -> Any:
    """A track file's path made absolute, relative to ``base_dir`` (a name stays one)."""
    if not isinstance(track, str) or track in shipped_tracks() or os.path.isabs(track):
        return track
    candidate = os.path.join(base_dir, track)
    return os.path.abspath(candidate) if os.path.exists(candidate) else track


def read_scenario_file(path: str | os.PathLike[str]) -> tuple[Any, Lines]:
    """A scenario file's mapping, its track made absolute (relative to the file), and its lines.

    Raises:
        FieldError: the file cannot be read, or is not valid YAML.
    """
    data, lines = read_yaml(path)
    if isinstance(data, dict) and "track" in data:
        data["track"] = absolute_track(data["track"], os.path.dirname(os.fspath(path)))
    return data, lines


def with_absolute_track(scenario: Scenario, base_dir: str = os.curdir) -> Scenario:
    """``scenario`` with a relative track file's path made absolute from ``base_dir``."""
    track = absolute_track(scenario.track, base_dir)
    return scenario if track == scenario.track else dataclasses.replace(scenario, track=track)


def load_scenario(
    path: str | os.PathLike[str] | None = None,
    overrides: Mapping[str, Any] | Iterable[Override] = (),
) -> Scenario:
    """A scenario from a YAML file (None: the defaults), with dotted overrides.

    A relative track path in the file is relative to the file; one given by
    an override, to the current directory.

    Raises:
        FieldError: the file cannot be read, or is not a valid scenario (one
            line naming the file, line and key).
    """
    if isinstance(overrides, Mapping):
        overrides = [Override(k, v) for k, v in overrides.items()]
    data: Any = None
    lines: Lines = {}
    source = None
    if path is not None:
        source = os.fspath(path)
        data, lines = read_scenario_file(path)
    return with_absolute_track(scenario_from_mapping(data, overrides, source=source, lines=lines))


def scenario_to_mapping(scenario: Scenario) -> dict[str, Any]:
    """The resolved scenario as plain data, every field filled in (see the module docstring)."""
    full = scenario.resolved()
    out: dict[str, Any] = {FORMAT_KEY: FORMAT_VERSION}
    out.update({key: plain(getattr(full, key)) for key in SCALARS})
    out["track"] = track_to_data(full.track)  # in its place: the order of SCALARS
    name = full.sensors.name
    out["sensors"] = {"profile": name if name in PROFILES else DEFAULT_PROFILE}
    out["sensors"].update(plain(full.sensors))
    out["faults"] = plain(full.faults)
    out["ekf"] = {"tuning": full.ekf_tuning, **plain(full.ekf, HIDDEN)}
    # the preset the fields start from: with every field listed, only a label
    preset = "cautious" if full.autopilot == AutopilotConfig.cautious() else "default"
    out["autopilot"] = {"preset": preset, **plain(full.autopilot, HIDDEN)}
    out["vehicle"] = plain(full.vehicle)
    out["global_path"] = plain(full.global_path)
    out["cone_map"] = plain(full.cone_map)
    out["slam"] = plain(full.slam)
    return out


SHOW_HEADER = "# conesim scenario, every default filled in: `conesim run FILE` runs it again.\n"


def scenario_yaml(scenario: Scenario) -> str:
    """``scenario_to_mapping`` as YAML text, with a one-line header."""
    return SHOW_HEADER + dump_yaml(scenario_to_mapping(scenario))
