"""The step the fusion EKF calls for a cone scan when it builds the map: EKF-SLAM.

Each scan, with the prior: the vehicle's (x, P) and the landmarks' part
of the state beside it (``localization.ekf.augmented.MapState``):

1. **association**, the map mode's (``localization.cones.association``),
   against the landmarks as they stand in the state, each pair gated with
   the landmark's covariance and its correlation with the pose;
2. **the joint update** of the pose and the matched landmarks: the map
   mode's stacked model (``localization.cones.observation``) with each
   landmark's own columns in H, gated by the joint NIS (the filter's);
3. **the map step** (:meth:`SlamUpdate.map_step`): colour votes, hits and
   misses; landmarks missed too often removed (marginalised); unexplained
   detections to the candidates (``localization.slam.book``), and the
   candidates seen in ``confirm_scans`` scans added to the state from this
   scan's detection (with its correlation with the pose).

Once the pose has driven ``min_loop_distance`` and come back within
``loop_radius`` of the start, the loop is closed and the map frozen: no
landmark enters or leaves after that (a cone that appears after the first
lap is a false positive), and the landmarks stay in the state but no longer
move (the Schmidt update of ``localization.ekf.augmented``): their
uncertainty and its correlation with the pose still enter every update, so
the NIS stays honest. Why frozen rather than refined on every lap: the
map's common motion (a rotation about the start, a shift) is observable
only through the biased GPS and heading, and a map kept updating drifts
with them (measured: 0.5 deg and 0.4 m over a second lap, its NEES per
dof twice its share), while the first lap's map, closed at the start it
began from, is the one reported and saved.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from numpy.typing import NDArray

from conesim.core.pose import Pose2D
from conesim.localization.cones.association import Association, StateCones, associate
from conesim.localization.cones.config import ConeUpdateConfig
from conesim.localization.cones.landmarks import LandmarkMap, colour_classes
from conesim.localization.cones.observation import block_diagonal, h_cones, jacob_h_cones
from conesim.localization.cones.update import ScanUpdate, StackedModel
from conesim.localization.ekf import augmented
from conesim.localization.ekf.augmented import MapState
from conesim.localization.ekf.health import ConeCounts
from conesim.localization.ekf.measurements import Measurement
from conesim.localization.ekf.model import YAW, X, Y
from conesim.localization.slam.book import MapBook
from conesim.localization.slam.config import SlamConfig

FloatArray = NDArray[np.float64]


class SlamUpdate(ScanUpdate):
    """Cone scans that build the map they localize against (module docstring).

    Args:
        config: the detector's noise, gates and colours; its map errors are
            ignored (the map's error is the state's covariance).
        slam: candidates, pruning, the start and the loop.
        start: the antenna's pose on the start (the track's start pose):
            the filter starts there with ``slam.start_sigma`` instead of at
            the first fix; None starts at the fix.
    """

    maps_landmarks = True

    def __init__(
        self,
        config: ConeUpdateConfig | None = None,
        slam: SlamConfig | None = None,
        start: Pose2D | None = None,
    ) -> None:
        cfg = config or ConeUpdateConfig()
        super().__init__(dataclasses.replace(cfg, map_sigma=0.0, map_bias_sigma=0.0))
        self.slam = slam or SlamConfig()
        self.start = start
        self._last_map: tuple[FloatArray, LandmarkMap] | None = None

    def empty_book(self) -> MapBook:
        """The bookkeeping of an empty map."""
        return MapBook.empty()

    def landmark_map(self, lmap: MapState, book: MapBook) -> LandmarkMap | None:
        """The landmarks as they stand in the state, or None without any (the last one
        again while the positions and colours are the same: the frozen map's)."""
        if not book.size:
            return None
        classes = book.classes()
        last = self._last_map
        if last is not None and last[0] is lmap.x and np.array_equal(last[1].classes, classes):
            return last[1]
        cones = LandmarkMap(lmap.x.reshape(-1, 2), classes)
        self._last_map = (lmap.x, cones)
        return cones

    def associate(
        self, x: FloatArray, p: FloatArray, lmap: MapState, meas: Measurement, book: MapBook
    ) -> Association:
        """Match the scan's detections to the landmarks in the prior (x, P_vv and the map's
        part ``lmap``)."""
        classes = None if meas.labels is None else colour_classes(meas.labels)
        cones = self.landmark_map(lmap, book)
        if cones is None:
            k = len(meas.z)
            none = np.zeros(0, dtype=np.intp)
            counts = ConeCounts(scans=1, false_positives=k)
            return Association(none, none, counts, none, np.arange(k, dtype=np.intp))
        n = lmap.size
        cross = lmap.cross()[:, augmented.POSE].reshape(n, 2, 3).transpose(0, 2, 1)
        return associate(
            x, p, meas.z, meas.cov, classes=classes, lmap=cones, cfg=self.config,
            gate=self.pair_gate, landmarks=StateCones(cross, lmap.blocks()),
        )  # fmt: skip

    def model(
        self, x: FloatArray, lmap: MapState, meas: Measurement, found: Association
    ) -> StackedModel:
        """z, h(x), H and R of the associated detections, with ``x`` the vehicle's state: H
        over its states and then each matched landmark's two (``augmented.scan_terms``)."""
        cones = lmap.x.reshape(-1, 2)[found.landmarks]
        nv = len(x)
        columns = nv + 2 * np.arange(len(cones), dtype=np.intp)
        return StackedModel(
            z=meas.z[found.detections].reshape(-1, 1),
            hx=h_cones(x, cones, self.config.sensor_offset),
            jacobian=jacob_h_cones(x, cones, nv + 2 * len(cones), columns=columns),
            cov=block_diagonal(meas.cov[found.detections]),
        )

    def map_step(
        self,
        x: FloatArray,
        p: FloatArray,
        lmap: MapState,
        meas: Measurement,
        found: Association,
        *,
        used: bool,
        book: MapBook,
    ) -> tuple[MapState, MapBook]:
        """Step 3 (module docstring) after the scan's update (``used``: it was applied), with
        the vehicle's x and P_vv.

        Returns:
            (the map's part, the book) with landmarks added or removed; the
            given map's part when nothing changed.
        """
        cfg = self.slam
        classes = None if meas.labels is None else colour_classes(meas.labels)
        if used:
            det_classes = None if classes is None else classes[found.detections]
            book = book.counted(found.landmarks, det_classes, found.missed)
        start = None if self.start is None else np.array([self.start.x, self.start.y])
        book = book.moved(np.array([x.item(X), x.item(Y)]), start, cfg)
        if book.closed:
            return lmap, book
        stale = book.stale(cfg)
        if len(stale):
            lmap = augmented.remove_landmarks(lmap, stale)
            book = book.without(stale)
        fresh = found.unmatched
        if found.counts.scans_gated:  # a gated scan's pose is in doubt
            return lmap, book
        yaw = x.item(YAW)
        c, s = math.cos(yaw), math.sin(yaw)
        rel = meas.z[fresh] + np.asarray(self.config.sensor_offset)
        xy = np.column_stack(
            [x.item(X) + c * rel[:, 0] - s * rel[:, 1], x.item(Y) + s * rel[:, 0] + c * rel[:, 1]]
        )
        fresh_classes = None if classes is None else classes[fresh]
        book, confirm, votes = book.sighted(xy, fresh_classes, meas.stamp, cfg)
        room = max(cfg.max_landmarks - book.size, 0)
        confirm, votes = confirm[:room], votes[:room]
        if len(confirm):
            rows = fresh[confirm]
            lmap = augmented.add_landmarks(
                x, p, lmap, meas.z[rows], meas.cov[rows], offset=self.config.sensor_offset
            )
            book = book.added(votes)
        return lmap, book
