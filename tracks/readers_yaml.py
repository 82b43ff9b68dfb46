"""Readers for the YAML track formats: our own and fssim's.

Our own format (version 1)::

    conesim_track: 1
    name: trackdrive
    description: ...            # optional
    layout: closed              # closed | open | skidpad
    start_pose: [x, y, yaw]     # [m, m, rad] in reference; null: derive it
    global_path: trackdrive_path.csv   # file next to this one, or null
    cones:                      # any of the kinds, each a list of [x, y] [m]
      blue: [[x, y], ...]
      yellow: [...]
      orange: [...]
      big_orange: [...]
      unknown: [...]

fssim (REFERENCES.md, "Track file formats"; AMZ fssim ``tracks_yaml``):
``cones_left`` (blue), ``cones_right`` (yellow), ``cones_orange``,
``cones_orange_big`` (lists of [x, y]) and ``starting_pose_front_wing`` or
``starting_pose_cg`` ([x, y, yaw]). fssim places its car by the tip of the
front wing; the track's start pose is the CG's, ``FSSIM_CG_TO_FRONT_WING``
behind it along the heading (the default vehicle's CG-to-front-axle plus
front overhang, ``sim.vehicle_params``; a test keeps the two equal, as
``tracks`` may not import ``sim``). Known fssim extras that carry no cones
are ignored: ``tk_device`` (timekeeping device positions), ``lap_threshold``
and ``middle_points`` (written by fssim track editors). Any other key is an error.
"""

from __future__ import annotations

import math
from pathlib import Path

import yaml

from conesim.core.pose import Pose2D
from conesim.tracks import yamlnodes as yn
from conesim.tracks.errors import TrackFormatError
from conesim.tracks.kinds import CONE_KINDS, ConeKind, Layout
from conesim.tracks.rawtrack import RawCone, RawTrack

FORMAT_VERSION = 1
OWN_REQUIRED = {"conesim_track", "name", "layout", "cones"}
OWN_KEYS = OWN_REQUIRED | {"start_pose", "global_path", "description"}

FSSIM_CONES = {
    "cones_left": ConeKind.BLUE,
    "cones_right": ConeKind.YELLOW,
    "cones_orange": ConeKind.ORANGE,
    "cones_orange_big": ConeKind.BIG_ORANGE,
}
FSSIM_POSES = ("starting_pose_front_wing", "starting_pose_cg")
FSSIM_CG_TO_FRONT_WING = 1.515  # [m] CG to the front wing tip, along the heading
FSSIM_IGNORED = {"tk_device", "lap_threshold", "middle_points"}
FSSIM_KEYS = set(FSSIM_CONES) | set(FSSIM_POSES) | FSSIM_IGNORED


def read_conesim_yaml(root: yaml.Node, path: Path) -> RawTrack:
    """Parse our own format from its root node (see the module docstring)."""
    entries = yn.mapping(root, path, "conesim track")
    yn.check_keys(entries, OWN_KEYS, path, "conesim track")
    missing = sorted(OWN_REQUIRED - set(entries))
    if missing:
        raise TrackFormatError(
            f"conesim track: missing key {missing[0]!r} "
            f"(required: {', '.join(sorted(OWN_REQUIRED))})",
            path,
        )
    version = entries["conesim_track"]
    if not isinstance(version, yaml.ScalarNode) or version.value != str(FORMAT_VERSION):
        raise TrackFormatError(
            f"conesim_track: unsupported version {getattr(version, 'value', '?')!r}, "
            f"this reader knows version {FORMAT_VERSION}",
            path,
            yn.line_of(version),
        )
    raw = RawTrack(name=yn.text(entries["name"], path, "name"), layout=_layout(entries, path))
    if "description" in entries and not yn.is_null(entries["description"]):
        raw.description = yn.text(entries["description"], path, "description")
    if "start_pose" in entries and not yn.is_null(entries["start_pose"]):
        raw.start_pose = _pose(entries["start_pose"], path, "start_pose")
    if "global_path" in entries and not yn.is_null(entries["global_path"]):
        raw.global_path_file = _global_path(entries["global_path"], path)
    cones = entries["cones"]
    if yn.is_null(cones):
        return raw
    by_kind = yn.mapping(cones, path, "cones")
    yn.check_keys(by_kind, {str(k) for k in CONE_KINDS}, path, "cones")
    for kind in CONE_KINDS:
        if str(kind) in by_kind:
            for x, y, line in yn.points(by_kind[str(kind)], path, f"cones.{kind}"):
                raw.cones.append(RawCone(x, y, kind, line))
    return raw


def read_fssim_yaml(root: yaml.Node, path: Path) -> RawTrack:
    """Parse an fssim track from its root node (see the module docstring)."""
    entries = yn.mapping(root, path, "fssim track")
    yn.check_keys(entries, FSSIM_KEYS, path, "fssim track")
    raw = RawTrack()
    for key, kind in FSSIM_CONES.items():
        if key in entries:
            for x, y, line in yn.points(entries[key], path, key):
                raw.cones.append(RawCone(x, y, kind, line))
    for key in FSSIM_POSES:  # the front wing pose wins when both are given
        if key in entries and not yn.is_null(entries[key]):
            pose = _pose(entries[key], path, key)
            if key == "starting_pose_front_wing":
                pose = cg_pose_from_front_wing(pose)
            raw.start_pose = pose
            break
    return raw


def cg_pose_from_front_wing(front_wing: Pose2D) -> Pose2D:
    """The CG's pose from the front wing tip's (fssim ``starting_pose_front_wing``)."""
    d = FSSIM_CG_TO_FRONT_WING
    return Pose2D(
        front_wing.x - d * math.cos(front_wing.yaw),
        front_wing.y - d * math.sin(front_wing.yaw),
        front_wing.yaw,
    )


def is_fssim(entries: dict[str, yaml.Node]) -> bool:
    """Whether a mapping's keys look like an fssim track."""
    return any(key in entries for key in FSSIM_CONES)


def _layout(entries: dict[str, yaml.Node], path: Path) -> Layout:
    node = entries["layout"]
    value = yn.text(node, path, "layout")
    try:
        return Layout(value)
    except ValueError:
        allowed = ", ".join(str(v) for v in Layout)
        raise TrackFormatError(
            f"layout: {value!r} is not one of {allowed}", path, yn.line_of(node)
        ) from None


def _pose(node: yaml.Node, path: Path, what: str) -> Pose2D:
    x, y, yaw = yn.numbers(node, 3, path, what)
    return Pose2D(x, y, yaw)


def _global_path(node: yaml.Node, path: Path) -> Path:
    name = yn.text(node, path, "global_path")
    target = Path(name)
    if target.is_absolute():
        raise TrackFormatError(
            f"global_path: {name!r} must be a file name relative to the track file",
            path,
            yn.line_of(node),
        )
    resolved = path.parent / target
    if not resolved.is_file():
        raise TrackFormatError(
            f"global_path: {name!r} not found next to the track file", path, yn.line_of(node)
        )
    return resolved
