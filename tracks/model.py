"""The `Track` type: cones with their kinds, a start pose and derived geometry."""

from __future__ import annotations

import os
from dataclasses import dataclass, field, fields
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from conesim.core.pose import Pose2D
from conesim.tracks.derived import TrackGeometry
from conesim.tracks.errors import TrackFormatError
from conesim.tracks.geometry import build_geometry
from conesim.tracks.kinds import CONE_KINDS, ConeKind, Layout

FloatArray = NDArray[np.float64]

MAX_COORDINATE = 1.0e6  # [m] cones further from the origin than this are a units or data error


@dataclass(frozen=True, eq=False)
class Track:
    """A cone track in the `reference` frame (ENU, metres).

    The cones are stored grouped by kind in ``ConeKind`` order (blue, yellow,
    orange, big_orange, unknown), keeping the given order within a kind, so
    that writing and reading a track reproduces it exactly.

    Attributes:
        name: the track's name.
        cones: (n, 2) cone positions in `reference` [m], read-only.
        kinds: (n,) the kind of each cone.
        start_pose: where the vehicle's reference point starts, in `reference`.
        layout: ``closed`` (a loop), ``open`` (acceleration) or ``skidpad``.
        source: the file the track was read from, if any.
        global_path_file: the ROS pipeline's ``lat,lon,cov`` CSV that goes with
            the track, if any.
        description: free text.

    Two tracks are equal when name, layout, cones, kinds, start pose and
    description are; ``source`` and ``global_path_file`` record provenance
    and are not compared.

    Derived geometry (computed once, on first use; arrays read-only):
    ``centreline``, ``widths``, ``left_boundary``, ``right_boundary``,
    ``start_finish``, ``finish_line``, ``direction``, ``length_m``.
    """

    name: str
    cones: FloatArray
    kinds: tuple[ConeKind, ...]
    start_pose: Pose2D
    layout: Layout = Layout.CLOSED
    source: Path | None = field(default=None)
    global_path_file: Path | None = field(default=None)
    description: str = ""

    def __post_init__(self) -> None:
        cones = _as_cones(self.cones)
        try:
            kinds = tuple(ConeKind(k) for k in self.kinds)
            layout = Layout(self.layout)
        except ValueError as exc:
            raise TrackFormatError(f"Track {self.name!r}: {exc}") from None
        if len(kinds) != len(cones):
            raise TrackFormatError(
                f"Track {self.name!r}: {len(cones)} cones but {len(kinds)} kinds"
            )
        if not isinstance(self.start_pose, Pose2D):
            raise TrackFormatError(f"Track {self.name!r}: start_pose must be a Pose2D")
        rank = np.array([CONE_KINDS.index(k) for k in kinds], dtype=int)
        order = np.argsort(rank, kind="stable")
        cones = cones[order]
        cones.setflags(write=False)
        object.__setattr__(self, "cones", cones)
        object.__setattr__(self, "kinds", tuple(kinds[i] for i in order))
        object.__setattr__(self, "layout", layout)
        for name in ("source", "global_path_file"):
            value = getattr(self, name)
            if value is not None:
                object.__setattr__(self, name, Path(os.fspath(value)))

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Track):
            return NotImplemented
        return (
            self.name == other.name
            and self.layout == other.layout
            and self.kinds == other.kinds
            and np.array_equal(self.cones, other.cones)
            and self.start_pose == other.start_pose
            and self.description == other.description
        )

    __hash__ = None  # type: ignore[assignment]  # mutable-looking arrays inside

    def __reduce__(self) -> tuple[Any, ...]:
        # Through the constructor, so that the unpickled cones are read-only again;
        # derived geometry travels along if it was computed.
        values = {f.name: getattr(self, f.name) for f in fields(self)}
        values["cones"] = np.array(self.cones)
        return _unpickle, (values, self.__dict__.get("geometry"))

    def cones_of(self, kind: ConeKind | str) -> FloatArray:
        """(k, 2) the cones of one kind [m], read-only."""
        mask = np.array([k == kind for k in self.kinds], dtype=bool)
        selected = self.cones[mask] if len(mask) else np.zeros((0, 2))
        selected.setflags(write=False)
        return selected

    def counts(self) -> dict[ConeKind, int]:
        """Number of cones of every kind (zero included), in ``ConeKind`` order."""
        return {kind: sum(1 for k in self.kinds if k == kind) for kind in CONE_KINDS}

    @cached_property
    def geometry(self) -> TrackGeometry:
        """Everything derived from the cones (computed once)."""
        return build_geometry(self.cones, self.kinds, self.layout, self.start_pose)

    @property
    def centreline(self) -> FloatArray:
        """(m, 2) true centreline [m], ~0.5 m apart, in the driving direction.

        A loop starts at the start/finish line and does not repeat its first
        point; an open lane and the skidpad run from the lane's start to its end.
        """
        return self.geometry.centreline

    @property
    def widths(self) -> FloatArray:
        """(m,) track width at each centreline point [m]."""
        return self.geometry.widths

    @property
    def left_boundary(self) -> FloatArray:
        """(p, 2) left boundary in driving order [m]: the blue cones and the
        orange cones on the left (skidpad: the centreline offset by width / 2)."""
        return self.geometry.left_boundary

    @property
    def right_boundary(self) -> FloatArray:
        """(q, 2) right boundary in driving order [m] (yellow, orange on the right)."""
        return self.geometry.right_boundary

    @property
    def start_finish(self) -> FloatArray:
        """(2, 2) the start/finish line's left and right end points [m]."""
        return self.geometry.start_finish

    @property
    def finish_line(self) -> FloatArray:
        """(2, 2) the line that ends a timed run [m]; a loop's start/finish line."""
        return self.geometry.finish_line

    @property
    def direction(self) -> FloatArray:
        """(2,) unit vector of driving at the start/finish line."""
        return self.geometry.direction

    @property
    def length_m(self) -> float:
        """Length of the centreline [m]: one lap of a loop, the whole lane otherwise."""
        return self.geometry.length_m


def _unpickle(values: dict[str, Any], geometry: TrackGeometry | None) -> Track:
    track = Track(**values)
    if geometry is not None:
        track.__dict__["geometry"] = geometry
    return track


def _as_cones(cones: ArrayLike) -> FloatArray:
    try:
        array = np.array(cones, dtype=float)
    except (TypeError, ValueError) as exc:
        raise TrackFormatError(f"cones must be an (n, 2) array of numbers: {exc}") from None
    if array.size == 0:
        array = array.reshape(0, 2)
    if array.ndim != 2 or array.shape[1] != 2:
        raise TrackFormatError(f"cones must be an (n, 2) array, got shape {array.shape}")
    if not np.all(np.isfinite(array)):
        raise TrackFormatError("cone positions must be finite (got NaN or inf)")
    if np.any(np.abs(array) > MAX_COORDINATE):
        raise TrackFormatError(f"cone positions must lie within {MAX_COORDINATE:g} m of the origin")
    return array
