"""The last few scans' cones, so that a cone one scan missed is still a boundary.

A detector misses cones: the rtk profile's own misses grow with range, and
a harsh scenario misses 30 % more of them, independently every scan. The
seed's pipeline plans from one scan, and with a third of a bend's cones
gone the Delaunay bridges join cones across the gaps: the midline ran into
the inside of bends at 11-16 m/s (``benchmarks/bench_driving.py``, tuning
seeds). A cone seen in one of the last scans stands where it stood (the
car's pose, from the frame tree, moves the scans into one frame), so the
planner is given each scan with the cones its memory holds and the scan
lacks.

``ConeMemory.recall``, per scan:

1. the scan's cones into ``reference`` (the frame tree, at the stamp the
   caller chose);
2. each matched to the nearest remembered cone within ``match_radius``
   (scipy's KD-tree; one scan's cone per remembered cone, nearest first),
   which moves to the running mean of its sightings and counts one more;
   a cone matched to none is remembered from now on;
3. cones not seen in the last ``keep_scans`` scans are forgotten;
4. the scan, plus the remembered cones it lacks that were seen at least
   ``min_sightings`` times (a false positive, a ghost of one scan, is not
   recalled), back in the scan's frame, nearest first. A colour-labelled
   scan's cones take their memory's most frequent label once seen
   ``min_sightings`` times (a label swapped in one scan of several is
   outvoted).

Hand-written because it is a few array operations around scipy's KD-tree;
the cone map of ``localization.cones`` is a survey the pose is corrected
against, not a short memory of what was seen.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from conesim.core.messages import CONE_COLOURS, ConeDetections
from conesim.localization.frames import Buffer
from conesim.planner.config import ConeMemoryConfig
from conesim.planner.geometry import FloatArray


class ConeMemory:
    """The cones of the last scans, in ``reference`` (module docstring).

    Attributes:
        points: (m, 2) remembered cones in ``reference`` [m].
        sightings: (m,) how often each was seen.
        last_scan: (m,) the scan each was last seen in.
        votes: (m, k) sightings per label of ``CONE_COLOURS``.
        scans: scans taken so far.
        recalled_count: remembered cones added to scans so far.
        recalled: (n,) which rows of the last scan ``recall`` returned are
            remembered cones rather than the scan's own (a map of what was
            seen must not count the memory's echoes as sightings).
    """

    def __init__(self, config: ConeMemoryConfig | None = None) -> None:
        self.config = config or ConeMemoryConfig()
        self.points: FloatArray = np.zeros((0, 2))
        self.sightings: NDArray[np.int64] = np.zeros(0, dtype=np.int64)
        self.last_scan: NDArray[np.int64] = np.zeros(0, dtype=np.int64)
        self.votes: NDArray[np.int64] = np.zeros((0, len(CONE_COLOURS)), dtype=np.int64)
        self.scans = 0
        self.recalled_count = 0
        self.recalled: NDArray[np.bool_] = np.zeros(0, dtype=bool)

    def recall(
        self, message: ConeDetections, buffer: Buffer, reference_frame: str, time: float
    ) -> ConeDetections:
        """The scan with the remembered cones it lacks (module docstring), in its frame.

        ``time``: when to look the scan's frame up in ``reference`` (its stamp,
        or ``LATEST``). Raises the frame tree's errors, remembering nothing then.
        """
        c = self.config
        if not c.enabled:
            self.recalled = np.zeros(len(message.points), dtype=bool)
            return message
        to_reference = buffer.lookup_transform(reference_frame, message.header.frame_id, time)
        scan = np.asarray(message.points, dtype=float)
        seen = to_reference.transform_points(scan[:, :2]) if len(scan) else np.zeros((0, 2))
        labels = (
            None
            if message.colours is None
            else np.array([CONE_COLOURS.index(k) for k in message.colours], dtype=np.int64)
        )
        self.scans += 1
        index = self._match(seen)
        new = index < 0
        index[new] = len(self.points) + np.arange(int(new.sum()))
        self._grow(seen[new])
        matched = index[~new]
        n = self.sightings[matched]
        self.points[matched] += (seen[~new] - self.points[matched]) / (n + 1)[:, None]
        self.sightings[index] += 1
        self.last_scan[index] = self.scans
        if labels is not None:
            np.add.at(self.votes, (index, labels), 1)
        index = self._forget()[index]  # the scan's cones are all kept: seen now
        trusted = self.sightings >= c.min_sightings
        in_scan = np.zeros(len(self.points), dtype=bool)
        in_scan[index] = True
        lacking = np.flatnonzero(~in_scan & trusted)
        self.recalled_count += len(lacking)
        if len(lacking) == 0 and labels is None:
            self.recalled = np.zeros(len(scan), dtype=bool)
            return message
        recalled = to_reference.inverse().transform_points(self.points[lacking])
        points = np.vstack([scan, np.column_stack([recalled, np.zeros(len(recalled))])])
        colours = None
        if labels is not None:
            voted = np.argmax(self.votes, axis=1)
            scan_labels = np.where(trusted[index], voted[index], labels)
            codes = np.concatenate([scan_labels, voted[lacking]])
            colours = [CONE_COLOURS[int(k)] for k in codes]
        order = np.argsort(np.hypot(points[:, 0], points[:, 1]), kind="stable")
        self.recalled = (np.arange(len(points)) >= len(scan))[order]
        return ConeDetections(
            message.header,
            points[order],
            None if colours is None else tuple(colours[int(i)] for i in order),
        )

    def _match(self, seen: FloatArray) -> NDArray[np.int64]:
        """(n,) the remembered cone each seen one is, or -1: nearest pairs first,
        each remembered cone taken once, within ``match_radius``."""
        index = np.full(len(seen), -1, dtype=np.int64)
        if len(self.points) == 0 or len(seen) == 0:
            return index
        k = min(3, len(self.points))
        dist, near = cKDTree(self.points).query(
            seen, k=k, distance_upper_bound=self.config.match_radius
        )
        dist = np.asarray(dist).reshape(len(seen), k)
        near = np.asarray(near).reshape(len(seen), k)
        taken = np.zeros(len(self.points), dtype=bool)
        for flat in np.argsort(dist, axis=None, kind="stable"):
            i, j = divmod(int(flat), k)
            if not math.isfinite(float(dist[i, j])):
                break  # the rest are farther than match_radius
            m = int(near[i, j])
            if index[i] < 0 and not taken[m]:
                index[i] = m
                taken[m] = True
        return index

    def _grow(self, points: FloatArray) -> None:
        """Remember ``points`` (k, 2) as new cones, not yet seen."""
        k = len(points)
        self.points = np.vstack([self.points, points])
        self.sightings = np.concatenate([self.sightings, np.zeros(k, dtype=np.int64)])
        self.last_scan = np.concatenate([self.last_scan, np.zeros(k, dtype=np.int64)])
        self.votes = np.vstack([self.votes, np.zeros((k, self.votes.shape[1]), dtype=np.int64)])

    def _forget(self) -> NDArray[np.int64]:
        """Drop the cones not seen in the last ``keep_scans`` scans; returns each old
        row's new one (-1: dropped)."""
        keep = self.scans - self.last_scan < self.config.keep_scans
        rows = np.where(keep, np.cumsum(keep) - 1, -1)
        if not keep.all():
            self.points = self.points[keep]
            self.sightings = self.sightings[keep]
            self.last_scan = self.last_scan[keep]
            self.votes = self.votes[keep]
        return rows
