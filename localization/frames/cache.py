"""Per-frame storage of a link's transforms over time: tf2's TimeCache and StaticCache.

Every frame that has a parent owns one cache holding the transforms
``parent -> frame`` it has received, following ros2/geometry2
``tf2/src/cache.cpp`` and ``tf2/src/static_cache.cpp``:

- :class:`TimeCache` (dynamic links) keeps samples sorted by stamp. A lookup
  at a stored stamp returns that sample; between two stamps it interpolates,
  translation linearly and rotation by slerp (:mod:`.rigid`); before the
  oldest or after the newest stamp it raises :class:`ExtrapolationError`
  ("past" or "future"). A single sample therefore answers only at its own
  stamp, as in tf2.
- Pruning is relative to the newest stamp, not to the clock: after each
  insert, samples older than ``newest - cache_time`` are dropped (one exactly
  ``cache_time`` older is kept, as tf2 keeps it), so memory stays flat over a
  run of any length. A sample that is already older than that bound when it
  arrives is not stored and :meth:`TimeCache.insert` returns False (tf2's
  ``TF_OLD_DATA``).
- A sample at a stamp already held replaces it. (tf2 has varied here: ROS 2
  Humble ignores such data with ``TF_REPEATED_DATA``, later releases keep both
  and mostly answer with the newer.)
- :class:`StaticCache` holds one transform, valid at every time; a new one
  replaces it.

Storage: two parallel Python lists (stamps, and ``(tx, ty, tz, qx, qy, qz, qw)``
tuples) searched with :func:`bisect.bisect_left`, plus one slerp step per
neighbouring pair, computed with scipy when the pair is formed so that a
lookup only evaluates a sine and a cosine. Inserts are appends in the usual
in-order case; out-of-order inserts and pruning shift a few hundred pointers.
"""

from __future__ import annotations

from bisect import bisect_left
from typing import Final, TypeAlias

from conesim.localization.frames import rigid
from conesim.localization.frames.errors import ExtrapolationError
from conesim.localization.frames.rigid import Rigid, SlerpStep

DEFAULT_CACHE_TIME: Final[float] = 10.0
"""tf2's default cache length [s]."""


class TimeCache:
    """The recent history of one dynamic link ``parent -> frame``.

    The buffer creates a cache together with its first sample; ``sample``,
    ``oldest`` and ``latest`` expect at least one.

    Args:
        frame: child frame name.
        parent: parent frame name.
        cache_time: how far behind the newest stamp samples are kept [s].
    """

    is_static: Final = False

    def __init__(self, frame: str, parent: str, cache_time: float = DEFAULT_CACHE_TIME) -> None:
        self.frame = frame
        self.parent = parent
        self.cache_time = cache_time
        self._stamps: list[float] = []
        self._samples: list[Rigid] = []
        self._steps: list[SlerpStep] = []  # _steps[k] goes from sample k to sample k + 1

    def __len__(self) -> int:
        return len(self._stamps)

    @property
    def oldest(self) -> float:
        """Oldest stamp held [s]."""
        return self._stamps[0]

    @property
    def latest(self) -> float:
        """Newest stamp held [s]."""
        return self._stamps[-1]

    @property
    def stamps(self) -> tuple[float, ...]:
        """All stamps held, oldest first [s]."""
        return tuple(self._stamps)

    def insert(self, stamp: float, sample: Rigid) -> bool:
        """Store a sample, then prune relative to the newest stamp.

        Args:
            stamp: sample time [s].
            sample: the transform ``(tx, ty, tz, qx, qy, qz, qw)``.

        Returns:
            False (and nothing changes) if ``stamp`` is older than the newest
            stamp minus ``cache_time``; True otherwise.
        """
        stamps = self._stamps
        if stamps and stamp < stamps[-1] - self.cache_time:
            return False
        i = bisect_left(stamps, stamp)
        if i < len(stamps) and stamps[i] == stamp:
            self._samples[i] = sample
        else:
            stamps.insert(i, stamp)
            self._samples.insert(i, sample)
            if len(stamps) > 1:
                self._steps.insert(min(i, len(self._steps)), rigid.NO_ROTATION)
        self._refresh_steps(i - 1, i)
        self._prune()
        return True

    def sample(self, time: float) -> Rigid:
        """The transform at ``time`` [s], interpolated between neighbouring stamps.

        Raises:
            ExtrapolationError: if ``time`` is before the oldest or after the
                newest stamp held.
        """
        stamps = self._stamps
        i = bisect_left(stamps, time)
        if i < len(stamps) and stamps[i] == time:
            return self._samples[i]
        if i == 0 or i == len(stamps):
            raise ExtrapolationError(self.frame, self.parent, time, stamps[0], stamps[-1])
        t0 = stamps[i - 1]
        ratio = (time - t0) / (stamps[i] - t0)
        return rigid.interpolate(self._samples[i - 1], self._samples[i], self._steps[i - 1], ratio)

    def _refresh_steps(self, *indices: int) -> None:
        """Recompute the slerp steps that start at the given sample indices."""
        for k in indices:
            if 0 <= k < len(self._steps):
                self._steps[k] = rigid.slerp_step(self._samples[k], self._samples[k + 1])

    def _prune(self) -> None:
        """Drop samples older than the newest stamp minus ``cache_time``."""
        cut = bisect_left(self._stamps, self._stamps[-1] - self.cache_time)
        if cut:
            del self._stamps[:cut]
            del self._samples[:cut]
            del self._steps[:cut]


class StaticCache:
    """The one transform of a static link ``parent -> frame``, valid at all times.

    Args:
        frame: child frame name.
        parent: parent frame name.
    """

    is_static: Final = True

    def __init__(self, frame: str, parent: str) -> None:
        self.frame = frame
        self.parent = parent
        self.stamp = 0.0
        self._sample: Rigid = rigid.IDENTITY

    def __len__(self) -> int:
        return 1

    def insert(self, stamp: float, sample: Rigid) -> bool:
        """Replace the stored transform; always True."""
        self.stamp = stamp
        self._sample = sample
        return True

    def sample(self, time: float) -> Rigid:
        """The stored transform, whatever ``time`` [s] is."""
        return self._sample


FrameCache: TypeAlias = TimeCache | StaticCache
