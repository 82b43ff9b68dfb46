"""What is derived from a track's cones: centreline, boundaries, widths, timing lines."""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Any

import numpy as np
from numpy.typing import NDArray

from conesim.tracks.kinds import ConeKind

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class SkidpadCircle:
    """One circle of the skidpad figure of eight, fitted to its cones.

    Attributes:
        centre: (2,) [m].
        r_inner: radius of the inner ring of cones [m].
        r_outer: radius of the outer ring of cones [m].
        inner_kind: the colour of the inner ring.
    """

    centre: FloatArray
    r_inner: float
    r_outer: float
    inner_kind: ConeKind

    def __post_init__(self) -> None:
        self.centre.setflags(write=False)

    def __reduce__(self) -> tuple[Any, ...]:
        return _rebuild, (type(self), _field_values(self))

    @property
    def radius(self) -> float:
        """Radius of the centreline on this circle, (r_inner + r_outer) / 2 [m]."""
        return 0.5 * (self.r_inner + self.r_outer)

    @property
    def width(self) -> float:
        """Track width on this circle, r_outer - r_inner [m]."""
        return self.r_outer - self.r_inner


@dataclass(frozen=True)
class TrackGeometry:
    """The true geometry of a track, derived once from its cones.

    Attributes:
        centreline: (m, 2) [m], ~0.5 m apart, in the driving direction. A loop
            starts at the start/finish line and does not repeat its first
            point; a lane (open, skidpad) runs from its start to its end.
        widths: (m,) track width at each centreline point [m].
        left_boundary: (p, 2) left boundary cones in driving order [m].
        right_boundary: (q, 2) right boundary cones in driving order [m].
        timing_lines: (2, 2) lines [m], each from its left to its right end,
            in driving order: the start/finish line first, the finish line
            (acceleration: at 75 m) last.
        direction: (2,) unit vector of driving at the start/finish line.
        length_m: length of the centreline [m] (a loop: one lap).
        closed: whether the centreline is a loop.
        curvature: (m,) signed curvature of the centreline [1/m], left positive
            (``Polyline.curvature``: the circle through each point and its neighbours).
        circles: skidpad only: the (right, left) circles, else None.
    """

    centreline: FloatArray
    widths: FloatArray
    left_boundary: FloatArray
    right_boundary: FloatArray
    timing_lines: tuple[FloatArray, ...]
    direction: FloatArray
    length_m: float
    closed: bool
    curvature: FloatArray
    circles: tuple[SkidpadCircle, SkidpadCircle] | None = None

    def __post_init__(self) -> None:
        for name in ("centreline", "widths", "left_boundary", "right_boundary", "direction"):
            getattr(self, name).setflags(write=False)
        self.curvature.setflags(write=False)
        for line in self.timing_lines:
            line.setflags(write=False)

    def __reduce__(self) -> tuple[Any, ...]:
        # Through the constructor, so that unpickled arrays are read-only again.
        return _rebuild, (type(self), _field_values(self))

    @property
    def start_finish(self) -> FloatArray:
        """(2, 2) the start (and, on a loop, finish) line [m]."""
        return self.timing_lines[0]

    @property
    def finish_line(self) -> FloatArray:
        """(2, 2) the line where the timed run ends [m] (a loop: the start/finish line)."""
        return self.timing_lines[-1]


def _field_values(obj: Any) -> dict[str, Any]:
    return {f.name: getattr(obj, f.name) for f in fields(obj)}


def _rebuild(cls: type[Any], values: dict[str, Any]) -> Any:
    """Unpickle a frozen dataclass through its constructor (re-running its checks)."""
    return cls(**{k: (np.array(v) if isinstance(v, np.ndarray) else v) for k, v in values.items()})
