"""Sweep files: a base scenario and the axes to vary, expanded into runs.

The format (version 1)::

    conesim_sweep: 1
    base: example.yaml       # a scenario file (relative to this file), or a scenario mapping
    axes:                    # dotted scenario keys and their values: the runs are the product
      track: [acceleration, skidpad]
      seed: {range: [0, 10]}           # 0, 1, ..., 9; [start, stop, step] takes a step
      sensors.profile: [rtk, consumer]
      faults:                          # named levels: a label and what it sets
        none: {}
        harsh: {cones: {detection_probability: 0.7}, gps: {multipath_rate: 0.05}}

or, instead of ``axes``, the runs one by one::

    points:
    - {track: skidpad, seed: 3}
    - {track: acceleration, faults.cones.detection_probability: 0.7}

Each value of an axis (each key of a point) is a dotted override of the
base, applied as ``conesim run --set KEY=VALUE`` applies it
(``envs.scenario_file.apply_override``), so it is checked exactly as
``--set`` is. A mapping value is merged into the base: each of its leaves is
its own override (``faults: {cones: {detection_probability: 0.7}}`` sets
that one field and keeps the base's other faults; ``{}`` changes nothing).
An axis's values are a list (each labelled by its value), a mapping of
labels to values (named levels), or ``{range: [start, stop]}`` /
``{range: [start, stop, step]}`` (integers, stop excluded).

The runs are expanded, and every run's scenario resolved and checked, when
the file is loaded: a problem is one ``FieldError`` naming the file and
line, before any run starts. A track file given in the sweep file is
relative to it. A point given twice (the same labels, the same resolved
scenario) is refused. A mapping whose only key is ``range`` is a range.
Each run has an id derived from its point alone (its axis labels and a
digest of its resolved scenario), which ``conesim sweep`` uses to skip what
is done when it resumes.
"""

from __future__ import annotations

import functools
import hashlib
import itertools
import json
import math
import os
import re
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from conesim.envs.dataclass_io import FieldError, Path
from conesim.envs.scenario import Scenario
from conesim.envs.scenario_file import (
    Override,
    read_scenario_file,
    scenario_from_mapping,
    scenario_to_mapping,
    with_absolute_track,
)
from conesim.envs.yaml_io import Lines, dump_yaml, read_yaml
from conesim.tracks import GeneratedTrack, TrackFormatError, check_report, load_track, track_label
from conesim.tracks.global_path import GlobalPathError

FORMAT_KEY = "conesim_sweep"
FORMAT_VERSION = 1
TOP_KEYS = (FORMAT_KEY, "base", "axes", "points")
MAX_RUNS = 100_000
"""A sweep of more runs than this is refused (a range typed with one zero too many)."""
BASE_LABEL = "(base)"
"""A point of a ``points`` list that does not set an axis has the base's value: this label."""


@dataclass(frozen=True)
class SweepPoint:
    """One run of a sweep.

    Attributes:
        index: its place in the sweep's order (0, 1, ...).
        labels: each axis's key and the label of this run's value, in axis order.
        scenario: the run's scenario (the base with the point's overrides).
        run_id: its id, stable for the same point: labels and scenario digest.
    """

    index: int
    labels: tuple[tuple[str, str], ...]
    scenario: Scenario
    run_id: str


@dataclass(frozen=True)
class Sweep:
    """A loaded sweep file: the axes' keys (in order) and every run.

    Attributes:
        source: the sweep file.
        axes: the axis keys, as the summary tables them.
        points: the runs, in order.
    """

    source: str
    axes: tuple[str, ...]
    points: tuple[SweepPoint, ...]

    @property
    def fingerprint(self) -> str:
        """A digest of every run's id: the same for the same runs, whatever the file's text."""
        digest = hashlib.sha256("\n".join(p.run_id for p in self.points).encode())
        return digest.hexdigest()[:16]


@dataclass(frozen=True)
class _Value:
    """One value of an axis: its label and its overrides."""

    label: str
    overrides: tuple[Override, ...]


def label_of(value: Any) -> str:
    """A value as a short label, on one line: ``0.7``, ``true``, ``consumer``, ``[10.0, 12.0]``.

    >>> label_of(0.7), label_of(True), label_of("rtk"), label_of([1, 2]), label_of(None)
    ('0.7', 'true', 'rtk', '[1, 2]', 'null')
    >>> label_of({"generate": {"seed": 3, "size": "small"}})
    '{generate: {seed: 3, size: small}}'
    """
    if isinstance(value, str):
        return value
    return dump_yaml(value, flow=True).strip().removesuffix("\n...").replace("\n", " ")


def _leaves(key: str, value: Any) -> list[tuple[str, Any]]:
    """A mapping value as its leaves' dotted keys (see the module docstring)."""
    if not isinstance(value, Mapping):
        return [(key, value)]
    out = []
    for name, item in value.items():
        if not isinstance(name, str) or not name:
            raise FieldError((), f"key {name!r} under {key}: expected a name")
        out += _leaves(f"{key}.{name}", item)
    return out


class _Reader:
    """Checks a sweep file's parts, naming the file and line of each problem."""

    def __init__(self, source: str, lines: Lines) -> None:
        self.source = source
        self.lines = lines

    def where(self, path: Path) -> str:
        for n in range(len(path), 0, -1):
            if path[:n] in self.lines:
                return f"{self.source}:{self.lines[path[:n]]}"
        return self.source

    def error(self, path: Path, reason: str) -> FieldError:
        return FieldError(path, reason, self.where(path))

    def value(self, path: Path, key: str, value: Any, label: str) -> _Value:
        """One value (of an axis or a point) as its overrides."""
        try:
            leaves = _leaves(key, value)
        except FieldError as exc:
            raise self.error(path, exc.reason) from None
        origin = self.where(path)
        return _Value(label, tuple(Override(k, v, origin) for k, v in leaves))

    def axis(self, key: Any, spec: Any) -> list[_Value]:
        """An axis's values: a list, named levels, or a range."""
        path = ("axes", str(key))
        if not isinstance(key, str) or not all(key.split(".")):
            raise self.error(path, f"bad key {key!r}: expected names joined by dots")
        if isinstance(spec, Mapping) and list(spec) == ["range"]:
            return [
                self.value((*path, "range"), key, n, str(n))
                for n in self.range((*path, "range"), spec["range"])
            ]
        if isinstance(spec, Mapping):
            items = [(str(label), value, (*path, label)) for label, value in spec.items()]
        elif isinstance(spec, list):
            items = [(label_of(value), value, (*path, i)) for i, value in enumerate(spec)]
        else:
            raise self.error(
                path, f"expected a list of values, a mapping of labels, or {{range: [start, stop]}}"
                f", got {spec!r}",
            )  # fmt: skip
        if not items:
            raise self.error(path, "has no values")
        seen: dict[str, int] = {}
        for i, (label, _, _) in enumerate(items):
            if label in seen:
                raise self.error(items[i][2], f"value {label!r} given twice")
            seen[label] = i
        return [self.value(p, key, value, label) for label, value, p in items]

    def range(self, path: Path, spec: Any) -> range:
        """``[start, stop]`` or ``[start, stop, step]``, integers, not empty."""
        if not (
            isinstance(spec, list)
            and len(spec) in (2, 3)
            and all(isinstance(n, int) and not isinstance(n, bool) for n in spec)
        ):
            raise self.error(
                path, f"expected [start, stop] or [start, stop, step] (integers), got {spec!r}"
            )
        if len(spec) == 3 and spec[2] == 0:
            raise self.error(path, "step must not be 0")
        values = range(*spec)
        if not values:
            raise self.error(path, f"{spec!r} is empty (stop is excluded)")
        if len(values) > MAX_RUNS:
            raise self.error(path, f"{len(values)} values; at most {MAX_RUNS}")
        return values

    def product(self, axes: Any) -> tuple[tuple[str, ...], list[list[tuple[str, _Value]]]]:
        """The axes' keys and the runs, each a list of (axis, value), axes varying last-first."""
        if not isinstance(axes, Mapping) or not axes:
            raise self.error(("axes",), "expected a mapping of dotted keys to their values")
        values = {key: self.axis(key, spec) for key, spec in axes.items()}
        count = math.prod(len(v) for v in values.values())
        if count > MAX_RUNS:
            raise self.error(("axes",), f"{count} runs; at most {MAX_RUNS}")
        keys = tuple(values)
        runs = [
            list(zip(keys, combo, strict=True)) for combo in itertools.product(*values.values())
        ]
        return keys, runs

    def points(self, points: Any) -> tuple[tuple[str, ...], list[list[tuple[str, _Value]]]]:
        """The keys any point sets (in order of first use) and the runs."""
        if not isinstance(points, list) or not points:
            raise self.error(("points",), "expected a list of runs, each a mapping of dotted keys")
        if len(points) > MAX_RUNS:
            raise self.error(("points",), f"{len(points)} runs; at most {MAX_RUNS}")
        keys: dict[str, None] = {}
        runs = []
        for i, point in enumerate(points):
            if not isinstance(point, Mapping):
                raise self.error(("points", i), f"expected a mapping of dotted keys, got {point!r}")
            run = []
            for key, value in point.items():
                if not isinstance(key, str) or not all(key.split(".")):
                    raise self.error(
                        ("points", i, str(key)), f"bad key {key!r}: expected names joined by dots"
                    )
                keys[key] = None
                run.append((key, self.value(("points", i, key), key, value, label_of(value))))
            runs.append(run)
        return tuple(keys), runs


def _run_id(labels: tuple[tuple[str, str], ...], scenario: Scenario) -> str:
    """``seed=3_profile=rtk-1a2b3c4d5e``: the labels (shortened) and the scenario's digest."""
    text = json.dumps(scenario_to_mapping(scenario), sort_keys=True)
    digest = hashlib.sha256(text.encode()).hexdigest()[:10]
    slug = "_".join(f"{key.rsplit('.', 1)[-1]}={label}" for key, label in labels)
    slug = re.sub(r"[^A-Za-z0-9.=+-]+", "_", slug).strip("_.")[:80]
    return f"{slug}-{digest}" if slug else digest


def load_sweep(path: str | os.PathLike[str]) -> Sweep:
    """A sweep file, expanded, every run's scenario resolved and its track checked.

    Raises:
        FieldError: the first problem found (one line naming the file and line).
    """
    source = os.fspath(path)
    data, lines = read_yaml(path)
    reader = _Reader(source, lines)
    if not isinstance(data, Mapping):
        raise FieldError((), "expected a mapping with base and axes (or points)", source)
    for key in data:
        if key not in TOP_KEYS:
            raise reader.error(
                (str(key),), f"unknown key {key!r}; allowed keys: {', '.join(TOP_KEYS)}"
            )
    version = data.get(FORMAT_KEY, FORMAT_VERSION)
    if version != FORMAT_VERSION or isinstance(version, bool):
        raise reader.error((FORMAT_KEY,), f"unknown format version {version!r}; allowed: 1")
    if ("axes" in data) == ("points" in data):
        has = "both" if "axes" in data else "neither"
        raise FieldError(
            (), f"give either axes (their product) or points (a list); it has {has}", source
        )
    here = os.path.dirname(source)
    base, base_source, base_lines = _base(data.get("base"), reader, here)
    keys, runs = reader.product(data["axes"]) if "axes" in data else reader.points(data["points"])
    points = []
    seen: dict[str, int] = {}
    for index, run in enumerate(runs):
        overrides = [o for _, value in run for o in value.overrides]
        scenario = scenario_from_mapping(base, overrides, source=base_source, lines=base_lines)
        scenario = with_absolute_track(scenario, here)
        given = dict((key, value.label) for key, value in run)
        labels = tuple((key, given.get(key, BASE_LABEL)) for key in keys)
        run_id = _run_id(labels, scenario)
        if run_id in seen:
            raise FieldError(
                (), f"runs {seen[run_id] + 1} and {index + 1} are the same run (the same "
                "resolved scenario); give each point once", source,
            )  # fmt: skip
        seen[run_id] = index
        points.append(SweepPoint(index, labels, scenario, run_id))
    for track in sorted({p.scenario.track for p in points}, key=track_label):
        _check_track(track, source)
    return Sweep(source, keys, tuple(points))


def _base(value: Any, reader: _Reader, here: str) -> tuple[Any, str, Lines]:
    """The base scenario's mapping, where it came from and its lines."""
    if value is None or isinstance(value, Mapping):
        prefix = ("base",)
        lines = {p[1:]: n for p, n in reader.lines.items() if p[:1] == prefix}
        return dict(value or {}), reader.source, lines
    if not isinstance(value, str) or not value.strip():
        raise reader.error(
            ("base",), f"expected a scenario file or a scenario mapping, got {value!r}"
        )
    path = value if os.path.isabs(value) else os.path.join(here, value)
    data, lines = read_scenario_file(path)
    return data, path, lines


@functools.cache
def _track_errors(track: str | GeneratedTrack) -> tuple[str, ...]:
    return tuple(check_report(load_track(track))["errors"])


def _check_track(track: str | GeneratedTrack, source: str) -> None:
    """A track that cannot be read, or in which ``track check`` finds errors, is bad input."""
    try:
        errors = _track_errors(track)
    except (TrackFormatError, GlobalPathError, OSError) as exc:
        raise FieldError(("track",), str(exc), source) from None
    if errors:
        raise FieldError(("track",), f"{track_label(track)}: {errors[0]}", source)
