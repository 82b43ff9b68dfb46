"""The map's bookkeeping beside the filter's state: candidates, colour votes, hits and misses.

A :class:`MapBook` is immutable (its arrays read-only): each scan makes a new
one, and the filter keeps it in each history snapshot, so a replayed scan
meets the book as it was before it, as it meets the state.

* **Candidates**: detections no landmark explains, in ``reference`` (with
  the pose after the scan's update). A detection within
  ``candidate_radius`` of a candidate is that candidate again (each
  candidate taken once a scan, the nearest first); after ``confirm_scans``
  sightings it becomes a landmark; one not seen for ``candidate_timeout``
  is dropped. A false positive, drawn anew each scan, stays a candidate for
  one scan.
* **Colours**: each landmark's votes (blue, yellow, orange) from the
  detections matched to it; its colour is the majority (``unknown`` without
  votes; ties go to the first).
* **Hits and misses**: scans that matched a landmark, and scans that had it
  in view and did not; ``misses - hits >= prune_misses`` removes it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Final, TypeVar

import numpy as np
from numpy.typing import NDArray

from conesim.localization.ekf.health import LandmarkCounts
from conesim.localization.slam.config import SlamConfig

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]

LABELS: Final = ("blue", "yellow", "orange")
"""The vote columns; the colour classes 0-2 of ``localization.cones.landmarks``."""


_A = TypeVar("_A", bound=np.ndarray)


def _frozen(a: _A) -> _A:
    a.setflags(write=False)
    return a


def _votes(classes: IntArray | None, k: int) -> FloatArray:
    """One-hot colour votes of ``k`` detections' classes (-1 or None: no vote), (k, 3)."""
    out = np.zeros((k, len(LABELS)))
    if classes is not None:
        ok = classes >= 0
        out[np.flatnonzero(ok), classes[ok]] = 1.0
    return out


@dataclass(frozen=True, slots=True)
class MapBook:
    """The map's bookkeeping (module docstring); ``empty()`` to start.

    Attributes:
        cand_xy: candidates' mean positions, (c, 2) [m].
        cand_seen: their sightings, (c,).
        cand_votes: their colour votes, (c, 3).
        cand_last: the stamp each was last seen [s], (c,).
        votes: each landmark's colour votes, (L, 3).
        hits: scans that matched each landmark, (L,).
        misses: scans that had it in view and did not, (L,).
        confirmed: landmarks ever confirmed [-].
        pruned: landmarks removed [-].
        closed: whether the loop has closed (the map's membership is final).
        travelled: the pose's path length so far, scan to scan [m].
        last_xy: the pose's position at the last scan, (2,), or None.
    """

    cand_xy: FloatArray
    cand_seen: IntArray
    cand_votes: FloatArray
    cand_last: FloatArray
    votes: FloatArray
    hits: IntArray
    misses: IntArray
    confirmed: int = 0
    pruned: int = 0
    closed: bool = False
    travelled: float = 0.0
    last_xy: FloatArray | None = None

    @classmethod
    def empty(cls) -> MapBook:
        """No candidates and no landmarks."""
        z2 = _frozen(np.zeros((0, 2)))
        zi = _frozen(np.zeros(0, dtype=np.intp))
        z3 = _frozen(np.zeros((0, 3)))
        zf = _frozen(np.zeros(0))
        return cls(z2, zi, z3, zf, z3, zi, zi)

    def _but(self, **changes: Any) -> MapBook:
        """The book with ``changes``: ``dataclasses.replace`` without its look-up of the
        fields on every call (a third of its time; each scan makes three or four books)."""
        get = changes.get
        return MapBook(
            get("cand_xy", self.cand_xy),
            get("cand_seen", self.cand_seen),
            get("cand_votes", self.cand_votes),
            get("cand_last", self.cand_last),
            get("votes", self.votes),
            get("hits", self.hits),
            get("misses", self.misses),
            get("confirmed", self.confirmed),
            get("pruned", self.pruned),
            get("closed", self.closed),
            get("travelled", self.travelled),
            get("last_xy", self.last_xy),
        )

    @property
    def size(self) -> int:
        """Landmarks in the map (in the state)."""
        return len(self.hits)

    def counts(self) -> LandmarkCounts:
        """Landmarks confirmed, tentative, pruned (``Health.landmarks``)."""
        return LandmarkCounts(
            self.size, len(self.cand_seen), self.pruned, self.confirmed, self.closed
        )

    def classes(self) -> IntArray:
        """Each landmark's colour class: the majority of its votes (ties to the first), or
        -1 without votes, (L,)."""
        best = np.argmax(self.votes, axis=1)
        best[~self.votes.any(axis=1)] = -1  # votes are counts, >= 0
        return best

    def labels(self) -> list[str]:
        """Each landmark's colour (:meth:`classes`' names, ``unknown`` for -1)."""
        return [LABELS[c] if c >= 0 else "unknown" for c in self.classes().tolist()]

    def counted(self, matched: IntArray, classes: IntArray | None, missed: IntArray) -> MapBook:
        """Landmarks ``matched`` (with their detections' ``classes``, (a,)) and ``missed``."""
        votes = self.votes.copy()
        np.add.at(votes, matched, _votes(classes, len(matched)))
        hits = self.hits.copy()
        hits[matched] += 1
        misses = self.misses.copy()
        misses[missed] += 1
        return self._but(votes=_frozen(votes), hits=_frozen(hits), misses=_frozen(misses))

    def stale(self, cfg: SlamConfig) -> IntArray:
        """The landmarks to remove: missed ``prune_misses`` scans more than matched."""
        return np.flatnonzero(self.misses - self.hits >= cfg.prune_misses)

    def without(self, drop: IntArray) -> MapBook:
        """The book with landmarks ``drop`` removed."""
        keep = np.ones(self.size, dtype=bool)
        keep[drop] = False
        return self._but(
            votes=_frozen(self.votes[keep]),
            hits=_frozen(self.hits[keep]),
            misses=_frozen(self.misses[keep]),
            pruned=self.pruned + len(drop),
        )

    def sighted(
        self, xy: FloatArray, classes: IntArray | None, stamp: float, cfg: SlamConfig
    ) -> tuple[MapBook, IntArray, FloatArray]:
        """Candidates after a scan's unexplained detections at ``xy`` (k, 2) in ``reference``.

        Returns:
            (the book, the detections that confirm a candidate (indices into
            ``xy``), those candidates' colour votes (c, 3)); the caller adds the
            landmarks (:meth:`added`).
        """
        alive = stamp - self.cand_last <= cfg.candidate_timeout
        cxy, seen = self.cand_xy[alive], self.cand_seen[alive]
        cvotes, last = self.cand_votes[alive], self.cand_last[alive]
        votes = _votes(classes, len(xy))
        owner = np.full(len(xy), -1, dtype=np.intp)
        if len(cxy) and len(xy):
            gap = np.linalg.norm(xy[:, None, :] - cxy[None, :, :], axis=2)
            for flat in np.argsort(gap, axis=None, kind="stable").tolist():
                i, j = divmod(flat, len(cxy))
                if gap[i, j] > cfg.candidate_radius:
                    break
                if owner[i] < 0 and not (owner == j).any():
                    owner[i] = j
        again = np.flatnonzero(owner >= 0)
        cxy, seen, cvotes, last = cxy.copy(), seen.copy(), cvotes.copy(), last.copy()
        j = owner[again]
        seen[j] += 1
        cxy[j] += (xy[again] - cxy[j]) / seen[j][:, None]
        cvotes[j] += votes[again]
        last[j] = stamp
        ready = seen >= cfg.confirm_scans
        confirm = again[ready[j]]
        confirm_votes = cvotes[owner[confirm]]
        fresh = np.flatnonzero(owner < 0)
        keep = ~ready
        book = self._but(
            cand_xy=_frozen(np.vstack([cxy[keep], xy[fresh]])),
            cand_seen=_frozen(np.concatenate([seen[keep], np.ones(len(fresh), dtype=np.intp)])),
            cand_votes=_frozen(np.vstack([cvotes[keep], votes[fresh]])),
            cand_last=_frozen(np.concatenate([last[keep], np.full(len(fresh), stamp)])),
        )
        return book, confirm, confirm_votes

    def added(self, votes: FloatArray) -> MapBook:
        """The book with landmarks appended, one per row of colour ``votes`` (c, 3)."""
        k = len(votes)
        zi = np.zeros(k, dtype=np.intp)
        return self._but(
            votes=_frozen(np.vstack([self.votes, votes])),
            hits=_frozen(np.concatenate([self.hits, zi + 1])),
            misses=_frozen(np.concatenate([self.misses, zi])),
            confirmed=self.confirmed + k,
        )

    def moved(self, xy: FloatArray, start: FloatArray | None, cfg: SlamConfig) -> MapBook:
        """The book after the pose reached ``xy`` (2,): path length, and the loop's closing."""
        travelled = self.travelled
        if self.last_xy is not None:
            travelled += float(np.hypot(*(xy - self.last_xy)))
        closed = self.closed or (
            start is not None
            and travelled >= cfg.min_loop_distance
            and float(np.hypot(*(xy - start))) <= cfg.loop_radius
        )
        return self._but(travelled=travelled, last_xy=_frozen(xy.copy()), closed=closed)
