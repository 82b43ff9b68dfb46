"""classify_cones_by_side: which cones bound the track on the left, which on the right.

The ROS pipeline's node, step by step:

1. ``cones_to_reference``: the detected cones (``os_sensor``, (n, 3)) are taken
   to the ground (z = 0, as the ROS pipeline does) and mapped into ``reference``
   through the frame tree at the detection's stamp.
2. ``PathProjector.project``: each cone is projected onto its nearest
   global-path segment (foot, station, signed offset, tangent). The ROS pipeline
   takes the nearest segment of the whole path; here segments outside the
   stretch from ``window_back`` behind to ``window_ahead`` ahead of the
   sensor's station count ``window_penalty`` farther, so that on a path that
   passes the same place twice (the skidpad's centre) a cone is read on the
   current pass, while a cone clearly nearer another stretch (behind the
   car, across a hairpin) still projects onto it. The sensor's station is
   ``station_hint`` (its last one; the autopilot keeps it) when given, and the
   sensor and the cones are then projected together; without a hint the
   sensor is first projected onto the whole path.
3. ``side_of_path``: the sign of the 2D cross product of the segment's
   direction with the vector from the segment to the cone: > 0 left, else
   right (the ROS pipeline's ``else`` branch takes a cone exactly on the path as right).

Colour mode (``ClassifierConfig.mode == "colour"``, the default) takes the
detector's colour where it names a side: ``left_colours`` (default blue) are
left, ``right_colours`` (default yellow) are right, following the FS rule
"blue on the left, yellow on the right" in the driving direction. Orange,
big orange, ``unknown`` and colour-blind detections fall back to the
geometric rule. A colour that contradicts the geometry (counted in
``ClassifiedCones.colour_disagreements``) is kept only where the cone stands
within ``geometry_overrules`` of the global path, where the geometry is
unsure; farther out the geometry decides: a detector that swaps blue and
yellow now and then (5 % of the cones) does not move a cone across the lane.
``mode = "geometric"`` is the ROS pipeline's colour-blind rule.

Cones with a non-finite coordinate are dropped and counted (messages do not
validate their numbers; ``localization.messages``).

Written for speed (it runs per detection): step 2's projections are compiled
searches (``PathProjector.project_around``, one call into ``planner.kernel_chains``),
step 1's finite rows and step 3's sides are compiled loops
(``kernels.ground_points``, ``kernels.side_of_path``: one call each instead
of a few numpy calls), and the default settings are built once.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from conesim.core.messages import FRAME_REFERENCE, ConeDetections, Header
from conesim.localization.frames import Buffer
from conesim.planner import kernels
from conesim.planner.config import ClassifierConfig
from conesim.planner.geometry import FloatArray, IntArray, PathProjector, StationAxis
from conesim.planner.messages import ConeMarker
from conesim.tracks.global_path import GlobalPath

LEFT = 1
RIGHT = -1
_DEFAULT_CONFIG = ClassifierConfig()  # frozen: built once


@dataclass(frozen=True, slots=True)
class ClassifiedCones:
    """Cones sorted by side, in ``reference`` (the ROS pipeline's left/right cone markers).

    Each array has one row per kept cone, in detection order.

    Attributes:
        header: the stamp of the transform used (the detection's, or the
            latest one's when ``time`` was ``LATEST``), frame ``reference``.
        points: (n, 2) cone positions [m].
        side: (n,) ``LEFT`` (+1) or ``RIGHT`` (-1).
        offset: (n,) signed distance from the nearest global-path segment,
            + left [m].
        station: (n,) arc length of the projection along the global path [m].
        tangent: (n, 2) unit direction of the nearest global-path segment.
        index: (n,) row of each cone in the detection.
        by_colour: (n,) True where the side came from the colour.
        sensor_station: station of ``os_sensor``'s projection at the stamp [m].
        axis: the global path's station axis.
        rejected: detections dropped for a non-finite coordinate.
        colour_disagreements: colour-classified cones on the other side of the
            global path.
    """

    header: Header
    points: FloatArray
    side: NDArray[np.int8]
    offset: FloatArray
    station: FloatArray
    tangent: FloatArray
    index: IntArray
    by_colour: NDArray[np.bool_]
    sensor_station: float
    axis: StationAxis
    rejected: int = 0
    colour_disagreements: int = 0

    @property
    def left(self) -> FloatArray:
        """(k, 2) left cones [m] (``/left_cone_marker``)."""
        return self.points[self.side == LEFT]

    @property
    def right(self) -> FloatArray:
        """(m, 2) right cones [m] (``/right_cone_marker``)."""
        return self.points[self.side == RIGHT]

    def markers(self) -> tuple[ConeMarker, ConeMarker]:
        """``/left_cone_marker`` and ``/right_cone_marker``."""
        return (
            ConeMarker(self.header, self.left, "left"),
            ConeMarker(self.header, self.right, "right"),
        )

    def __len__(self) -> int:
        return len(self.points)

    def select(self, keep: NDArray[np.bool_] | IntArray) -> ClassifiedCones:
        """The same classification restricted to ``keep`` (mask or indices)."""
        return ClassifiedCones(
            header=self.header,
            points=self.points[keep],
            side=self.side[keep],
            offset=self.offset[keep],
            station=self.station[keep],
            tangent=self.tangent[keep],
            index=self.index[keep],
            by_colour=self.by_colour[keep],
            sensor_station=self.sensor_station,
            axis=self.axis,
            rejected=self.rejected,
            colour_disagreements=self.colour_disagreements,
        )


def cones_to_reference(
    detections: ConeDetections,
    buffer: Buffer,
    time: float | None = None,
    reference_frame: str = FRAME_REFERENCE,
) -> tuple[FloatArray, FloatArray, NDArray[np.bool_], float]:
    """Step 1: detected cones on the ground, in ``reference``.

    Args:
        detections: cones in ``detections.header.frame_id``.
        buffer: the frame tree.
        time: lookup time [s]; None uses the detection's stamp.
        reference_frame: the world frame.

    Returns:
        (k, 2) finite cones in ``reference`` [m], (2,) the sensor's origin in
        ``reference`` [m], the (n,) mask of the finite detections, and the
        time the transform was taken at [s].

    Raises:
        The frame tree's errors (e.g. ``ExtrapolationError``) unchanged.
    """
    mapped, finite, stamp = _ground_to_reference(detections, buffer, time, reference_frame)
    return mapped[:-1], mapped[-1], finite, stamp


def _ground_to_reference(
    detections: ConeDetections, buffer: Buffer, time: float | None, reference_frame: str
) -> tuple[FloatArray, NDArray[np.bool_], float]:
    """``cones_to_reference`` with the sensor's origin as the last row of the cones."""
    stamp = detections.header.stamp if time is None else time
    transform = buffer.lookup_transform(reference_frame, detections.header.frame_id, stamp)
    # The finite rows' x and y, then the origin: compiled (one call, one copy).
    ground, finite = kernels.ground_points(np.asarray(detections.points, dtype=float))
    return transform.transform_points(ground), finite, transform.stamp


def side_of_path(offset: FloatArray) -> NDArray[np.int8]:
    """Step 3, the ROS pipeline's rule: ``LEFT`` where the cross product is > 0, else ``RIGHT``.

    Compiled (``kernels.side_of_path``): one loop instead of a comparison and a ``where``.
    """
    side: NDArray[np.int8] = kernels.side_of_path(np.ascontiguousarray(offset, dtype=float))
    return side


def side_from_colour(
    colours: tuple[str, ...] | None, n: int, config: ClassifierConfig
) -> NDArray[np.int8]:
    """The side each colour names in colour mode: ``LEFT``, ``RIGHT``, or 0 (no say)."""
    if colours is None:
        return np.zeros(n, dtype=np.int8)
    left = set(config.left_colours)
    right = set(config.right_colours)
    return np.array(
        [LEFT if c in left else RIGHT if c in right else 0 for c in colours], dtype=np.int8
    )


def classify_cones_by_side(
    detections: ConeDetections,
    buffer: Buffer,
    path: GlobalPath | PathProjector,
    config: ClassifierConfig | None = None,
    *,
    time: float | None = None,
    station_hint: float | None = None,
    reference_frame: str = FRAME_REFERENCE,
) -> ClassifiedCones:
    """Sort detected cones into left and right of the global path, in ``reference``.

    Args:
        detections: the cones (``/sorted_cones_time``), (n, 3) in ``os_sensor``.
        buffer: the frame tree.
        path: the global path, or a projector built on it once (faster).
        config: mode and colour rule; defaults to colour mode (``ClassifierConfig()``).
        time: lookup time [s]; None uses the detection's stamp.
        station_hint: the sensor's last station [m], if known.
        reference_frame: the world frame.

    Returns:
        The classified cones.

    Raises:
        The frame tree's errors unchanged (the autopilot decides what to do).
    """
    config = config or _DEFAULT_CONFIG
    projector = path if isinstance(path, PathProjector) else PathProjector(path.polyline)
    # The cones and, last, the sensor, whose station is the window's origin
    # (``station_hint``, or the sensor's own projection onto the whole path).
    both, finite, stamp = _ground_to_reference(detections, buffer, time, reference_frame)
    cones = both[:-1]
    proj = projector.project_around(
        both, config.window_back, config.window_ahead, config.window_penalty, station_hint
    )
    n = len(cones)
    offset = proj.offset[:n]
    side = side_of_path(offset)
    by_colour = np.zeros(n, dtype=bool)
    disagreements = 0
    if config.mode == "colour":
        named = side_from_colour(detections.colours, len(detections), config)[finite]
        disagree = (named != 0) & (named != side)
        disagreements = int(np.count_nonzero(disagree))
        # Where the geometry is clear, a colour that disagrees is a swap.
        by_colour = (named != 0) & ~(disagree & (np.abs(offset) > config.geometry_overrules))
        side = np.where(by_colour, named, side).astype(np.int8)
    rejected = len(finite) - n
    return ClassifiedCones(
        header=Header(stamp, reference_frame),
        points=cones,
        side=side,
        offset=offset,
        station=proj.station[:n],
        tangent=proj.tangent[:n],
        index=np.arange(n) if rejected == 0 else finite.nonzero()[0],
        by_colour=by_colour,
        sensor_station=float(proj.station[n]),
        axis=projector.axis,
        rejected=rejected,
        colour_disagreements=disagreements,
    )
