"""How good a map built while driving is (``slam`` localization): landmarks against the cones.

Each landmark is paired with at most one true cone and each cone with at
most one landmark, minimising the summed distance (``scipy.optimize.
linear_sum_assignment``), pairs farther apart than ``match_radius`` left
out. Then:

* **raw**: the paired distances as they are, in ``reference`` (what the
  issue calls the mean error of cone positions against truth);
* **aligned**: after the rigid motion (rotation and translation, Kabsch)
  that best fits the landmarks onto their cones, the map's shape alone: a
  map with a common offset localizes the car as well on its own (the car
  then stands off by the same offset);
* **missed**: true cones with no landmark; **spurious**: landmarks with no cone;
* **nees_per_dof**: e' P^-1 e / 2 over the pairs, raw: about 1 when the
  map's covariance is honest.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linear_sum_assignment

from conesim.sim.events import LapCompleted
from conesim.tracks import Track
from conesim.tracks.kinds import ConeKind

if TYPE_CHECKING:
    from conesim.envs.loop import ClosedLoop, StepRecord

FloatArray = NDArray[np.float64]

MATCH_RADIUS = 1.0  # [m] a landmark farther than this from every cone is spurious


@dataclass(frozen=True, slots=True)
class MapQuality:
    """A map's landmarks against the true cones (module docstring).

    Attributes:
        landmarks: landmarks in the map [-].
        cones: true cones [-].
        missed: true cones with no landmark within ``match_radius`` [-].
        spurious: landmarks with no true cone within it [-].
        mean_error_m, max_error_m: paired distances, raw [m].
        mean_error_aligned_m, max_error_aligned_m: after the best rigid fit [m].
        offset_m: the best fit's translation (its size) [m].
        rotation_deg: and its rotation [deg].
        nees_per_dof: e' P^-1 e / 2 over the pairs, raw [-].
    """

    landmarks: int
    cones: int
    missed: int
    spurious: int
    mean_error_m: float
    max_error_m: float
    mean_error_aligned_m: float
    max_error_aligned_m: float
    offset_m: float
    rotation_deg: float
    nees_per_dof: float

    def as_dict(self) -> dict[str, float]:
        """The fields by name (``result.json``'s ``map_quality``)."""
        return asdict(self)


def _rigid_fit(a: FloatArray, b: FloatArray) -> tuple[FloatArray, FloatArray]:
    """The rotation (2, 2) and translation (2,) that best map points ``a`` onto ``b`` (Kabsch)."""
    ca, cb = a.mean(axis=0), b.mean(axis=0)
    u, _, vt = np.linalg.svd((a - ca).T @ (b - cb))
    d = np.sign(np.linalg.det(vt.T @ u.T))
    rot = vt.T @ np.diag([1.0, d]) @ u.T
    return rot, cb - rot @ ca


def map_quality(
    landmarks: FloatArray,
    covariances: FloatArray,
    cones: FloatArray,
    match_radius: float = MATCH_RADIUS,
) -> MapQuality:
    """Score a map (module docstring).

    Args:
        landmarks: the map's positions, (L, 2) [m].
        covariances: their covariances, (L, 2, 2) [m^2].
        cones: the true cones, (n, 2) [m].
        match_radius: the farthest a landmark may stand from its cone [m].
    """
    nan = math.nan
    if not len(landmarks) or not len(cones):
        return MapQuality(len(landmarks), len(cones), len(cones), len(landmarks), *[nan] * 7)
    gap = np.linalg.norm(landmarks[:, None, :] - cones[None, :, :], axis=2)
    rows, cols = linear_sum_assignment(np.where(gap <= match_radius, gap, 1e6))
    ok = gap[rows, cols] <= match_radius
    rows, cols = rows[ok], cols[ok]
    pairs = len(rows)
    if not pairs:
        return MapQuality(len(landmarks), len(cones), len(cones), len(landmarks), *[nan] * 7)
    err = landmarks[rows] - cones[cols]
    dist = np.hypot(err[:, 0], err[:, 1])
    nees = np.einsum("qi,qi->q", err, np.linalg.solve(covariances[rows], err[..., None])[..., 0])
    if pairs >= 2:
        rot, shift = _rigid_fit(landmarks[rows], cones[cols])
    else:
        rot, shift = np.eye(2), -err[0]
    aligned = landmarks[rows] @ rot.T + shift - cones[cols]
    adist = np.hypot(aligned[:, 0], aligned[:, 1])
    return MapQuality(
        landmarks=len(landmarks),
        cones=len(cones),
        missed=len(cones) - pairs,
        spurious=len(landmarks) - pairs,
        mean_error_m=float(dist.mean()),
        max_error_m=float(dist.max()),
        mean_error_aligned_m=float(adist.mean()),
        max_error_aligned_m=float(adist.max()),
        offset_m=float(np.hypot(*shift)),
        rotation_deg=math.degrees(math.atan2(rot[1, 0], rot[0, 0])),
        nees_per_dof=float(nees.mean() / 2.0),
    )


@dataclass(frozen=True, slots=True)
class MapSnapshot:
    """The map built while driving at one moment, with the truth it is scored against.

    Attributes:
        t: when [s].
        lap: the laps completed then (1: right after the first) [-].
        positions: the landmarks, (L, 2) [m].
        covariances: their covariances, (L, 2, 2) [m^2].
        labels: their colours (majority votes).
        quality: the score against the cones as they stood then.
    """

    t: float
    lap: int
    positions: FloatArray
    covariances: FloatArray
    labels: tuple[str, ...]
    quality: MapQuality


class MapRecorder:
    """Keeps the map of a ``slam`` run after its first lap (or at its end, without one).

    ``observe`` each record of the loop; ``snapshot`` is the map after the
    first completed lap, else the last one taken (``finish``).
    """

    def __init__(self) -> None:
        self.snapshot: MapSnapshot | None = None
        self._after_lap = False

    def observe(self, loop: ClosedLoop, record: StepRecord) -> None:
        """Take the map when the record completes the first lap."""
        if self._after_lap or not any(
            isinstance(e, LapCompleted) and e.lap == 1 for e in record.events
        ):
            return
        self._after_lap = self._take(loop, record, 1)

    def finish(self, loop: ClosedLoop, record: StepRecord) -> None:
        """At the run's end: take the map if no lap was completed."""
        if not self._after_lap:
            self._take(loop, record, record.truth.race.laps_completed)

    def _take(self, loop: ClosedLoop, record: StepRecord, lap: int) -> bool:
        ekf = loop.localizer.ekf
        state = None if ekf is None else ekf.landmark_state()
        if state is None:
            return False
        xy, cov, book = state
        quality = map_quality(xy, cov, np.asarray(record.truth.cones))
        self.snapshot = MapSnapshot(record.t, lap, xy, cov, tuple(book.labels()), quality)
        return True


_KINDS: dict[str, ConeKind] = {
    "blue": ConeKind.BLUE,
    "yellow": ConeKind.YELLOW,
    "orange": ConeKind.ORANGE,
    "unknown": ConeKind.UNKNOWN,
}


def map_track(snapshot: MapSnapshot, track: Track) -> Track:
    """The map as a track (``conesim run --track`` loads it once written with
    ``tracks.write_track``): its landmarks as cones of their colour (orange
    for both orange kinds: the detector does not tell them apart), ``track``'s
    start pose and layout."""
    return Track(
        name=f"{track.name}_slam_map",
        cones=snapshot.positions,
        kinds=tuple(_KINDS[label] for label in snapshot.labels),
        start_pose=track.start_pose,
        layout=track.layout,
        description=(
            f"the cone map conesim's slam localization built on {track.name} "
            f"(after lap {snapshot.lap}, t = {snapshot.t:.2f} s)"
        ),
    )
