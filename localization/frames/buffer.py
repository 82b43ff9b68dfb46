"""The frame tree: a tf2-style buffer of stamped transforms between named frames.

Semantics follow tf2's ``BufferCore`` (ros2/geometry2 ``tf2/src/buffer_core.cpp``):

- ``set_transform(t)`` records ``t.child_frame_id``'s pose in ``t.frame_id``;
  such a transform maps points from the child into the parent.
- ``lookup_transform(target, source, time)`` returns a transform with
  ``frame_id = target`` and ``child_frame_id = source`` that maps points from
  ``source`` into ``target``. It walks from both frames up to their lowest
  common ancestor, composing each link at ``time``, and returns
  ``inverse(target -> ancestor) ∘ (source -> ancestor)``.
- Static links hold at every time; dynamic links are interpolated between
  their stamps and raise :class:`ExtrapolationError` outside them (see
  :mod:`.cache`). ``time == 0`` (:data:`LATEST`) means the latest time at
  which every dynamic link of the chain has data: the smallest of their
  newest stamps (tf2's ``getLatestCommonTime``), or 0 if all links are
  static. The returned transform is stamped with the time actually used.
  Sim time starts at 0 as well, so time 0 always means "latest", never
  "at t = 0 s"; the two agree only until later data arrives.
- ``lookup_transform_full(target, target_time, source, source_time, fixed)``
  is tf2's "advanced" (time-travel) lookup: ``(target <- fixed at
  target_time) ∘ (fixed <- source at source_time)``, each leg a
  ``lookup_transform`` with its own :data:`LATEST` handling. As tf2's
  ``BufferCore::lookupTransform`` (ros2/geometry2 ``buffer_core.cpp``), the
  result has ``frame_id = target`` and ``child_frame_id = source`` and is
  stamped with the time the target leg used.
- A leading ``/`` is stripped from every frame name, in inserts and lookups.
  A vehicle prefix (``car1/gps_antenna``) is part of the name, so several
  vehicles' trees can hang under one ``reference`` (tf2 has no ``tf_prefix``).

Where this differs from tf2, on purpose:

- Bad input raises instead of being logged and dropped:
  :class:`InvalidTransformError` for an empty name or a self-transform (and,
  when the :class:`TransformStamped` is built, for NaN/inf or a quaternion off
  unit norm by more than 1e-6), and :class:`FrameTreeError` for a second
  parent. tf2 lets a frame change parent over time; here a frame keeps the
  parent of its first transform, so the tree cannot silently change shape and
  a cycle is impossible (one is rejected before it forms). A rejected input
  leaves the buffer unchanged.
- Looking up a frame in itself requires that frame to exist (tf2 returns the
  identity for any name, which hides typos).
- Data older than the cache length is still dropped as in tf2 (``TF_OLD_DATA``):
  ``set_transform`` logs a warning and returns False.

As in tf2, switching a link between static and dynamic replaces its cache by
one of the new kind. The buffer is not thread-safe: one simulation loop owns it.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import Final, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from conesim.core.pose import Pose2D, wrap_angle
from conesim.localization.frames import rigid
from conesim.localization.frames.cache import DEFAULT_CACHE_TIME, FrameCache, StaticCache, TimeCache
from conesim.localization.frames.errors import (
    ConnectivityError,
    ExtrapolationError,
    FrameNotFoundError,
    FrameTreeError,
    FullLookup,
    InvalidArgumentError,
    InvalidTransformError,
    TransformError,
    full_lookup_context,
)
from conesim.localization.frames.rigid import Rigid
from conesim.localization.frames.transform import (
    TransformStamped,
    strip_leading_slash,
    transform_points_rigid,
)

LATEST: Final[float] = 0.0
"""Lookup time meaning "the latest time common to the whole chain" (tf2's ``Time(0)``)."""

DEFAULT_AUTHORITY: Final[str] = "default_authority"

_log = logging.getLogger(__name__)


@dataclass(frozen=True, slots=True)
class FrameInfo:
    """What the buffer holds for one frame that has a parent (tf2's ``allFramesAsYAML``).

    Attributes:
        parent: parent frame name.
        static: whether the link is static.
        authority: who sent the latest accepted transform.
        oldest: oldest stamp held [s] (the stamp of the transform if static).
        latest: newest stamp held [s] (the stamp of the transform if static).
        length: number of samples held.
    """

    parent: str
    static: bool
    authority: str
    oldest: float
    latest: float
    length: int


@dataclass(frozen=True, slots=True)
class _Chain:
    """The links between two frames, resolved once and reused until the tree changes."""

    target: str
    source: str
    up_from_source: tuple[FrameCache, ...]
    up_from_target: tuple[FrameCache, ...]
    dynamic: tuple[TimeCache, ...]

    def latest_common_time(self) -> float:
        """Smallest newest stamp over the chain's dynamic links [s]; 0 if none."""
        if not self.dynamic:
            return LATEST
        return min(cache.latest for cache in self.dynamic)


def _check_time(time: float, argument: str) -> None:
    """Raise InvalidArgumentError unless the lookup time ``argument`` is finite."""
    if not math.isfinite(time):
        raise InvalidArgumentError(f"{argument} must be finite, got {time!r}")


def _accumulate(links: tuple[FrameCache, ...], time: float) -> Rigid:
    """Compose the links from a frame up to an ancestor: frame -> ancestor."""
    if not links:
        return rigid.IDENTITY
    acc = links[0].sample(time)
    for k in range(1, len(links)):
        acc = rigid.compose(links[k].sample(time), acc)
    return acc


class Buffer:
    """A tree of frames linked by static and time-stamped dynamic transforms.

    Args:
        cache_time: how long each dynamic link's history is kept, measured
            back from its newest stamp [s]. tf2's default is 10 s.

    Raises:
        InvalidArgumentError: if ``cache_time`` is not finite and positive.
    """

    def __init__(self, cache_time: float = DEFAULT_CACHE_TIME) -> None:
        if not (math.isfinite(cache_time) and cache_time > 0.0):
            raise InvalidArgumentError(f"cache_time must be finite and > 0 s, got {cache_time!r}")
        self.cache_time = float(cache_time)
        self._links: dict[str, FrameCache] = {}  # keyed by child frame
        self._authority: dict[str, str] = {}
        self._frames: set[str] = set()
        self._chains: dict[tuple[str, str], _Chain] = {}

    # -- inserting ---------------------------------------------------------------------------

    def set_transform(
        self,
        transform: TransformStamped,
        authority: str = DEFAULT_AUTHORITY,
        static: bool = False,
    ) -> bool:
        """Record ``transform.child_frame_id``'s pose in ``transform.frame_id``.

        Args:
            transform: the transform; its values were checked when it was built.
            authority: who sends it (kept for :meth:`frames`).
            static: True for a link that holds at every time.

        Returns:
            True if stored; False if it is older than the link's newest stamp
            minus ``cache_time`` and was dropped (tf2's ``TF_OLD_DATA``).

        Raises:
            InvalidTransformError: an empty frame name or a self-transform.
            FrameTreeError: the child already has another parent, or the link
                would close a cycle.
        """
        parent = strip_leading_slash(transform.frame_id)
        child = strip_leading_slash(transform.child_frame_id)
        self._check_link(parent, child, authority)
        link = self._links.get(child)
        if link is None or link.is_static != static:
            self._add_link(parent, child, static).insert(transform.stamp, transform.rigid)
        elif not link.insert(transform.stamp, transform.rigid):
            _log.warning(
                "TF_OLD_DATA: ignoring transform '%s' -> '%s' from authority '%s' at %r s, "
                "older than the newest stamp %r s minus the cache time %r s",
                parent,
                child,
                authority,
                transform.stamp,
                link.latest if isinstance(link, TimeCache) else link.stamp,
                self.cache_time,
            )
            return False
        self._authority[child] = authority
        return True

    def set_transform_static(
        self, transform: TransformStamped, authority: str = DEFAULT_AUTHORITY
    ) -> bool:
        """Record a static transform: ``set_transform(transform, authority, static=True)``."""
        return self.set_transform(transform, authority, static=True)

    def _check_link(self, parent: str, child: str, authority: str) -> None:
        """Raise if the link ``parent -> child`` may not enter the tree."""
        if not parent or not child:
            raise InvalidTransformError(
                f"transform '{parent}' -> '{child}' from authority '{authority}': "
                "frame_id and child_frame_id must be non-empty"
            )
        if parent == child:
            raise InvalidTransformError(
                f"transform from authority '{authority}' has frame_id and child_frame_id "
                f"both '{child}' (a self-transform)"
            )
        link = self._links.get(child)
        if link is not None:
            if link.parent != parent:
                raise FrameTreeError(
                    f"frame '{child}' already has parent '{link.parent}'; transform "
                    f"'{parent}' -> '{child}' from authority '{authority}' would give it a "
                    "second parent (re-parenting is not supported)"
                )
            return
        ancestor: str | None = parent
        while ancestor is not None:
            if ancestor == child:
                raise FrameTreeError(
                    f"transform '{parent}' -> '{child}' from authority '{authority}' would "
                    f"close a cycle: '{child}' is already an ancestor of '{parent}'"
                )
            above = self._links.get(ancestor)
            ancestor = above.parent if above is not None else None

    def _add_link(self, parent: str, child: str, static: bool) -> FrameCache:
        """Create (or replace) the cache of ``child``; the tree's shape changes."""
        link: FrameCache = (
            StaticCache(child, parent) if static else TimeCache(child, parent, self.cache_time)
        )
        self._links[child] = link
        self._frames.update((parent, child))
        self._chains.clear()
        return link

    # -- looking up --------------------------------------------------------------------------

    def lookup_transform(
        self, target_frame: str, source_frame: str, time: float
    ) -> TransformStamped:
        """The transform mapping points from ``source_frame`` into ``target_frame``.

        Args:
            target_frame: frame the result maps into (its ``frame_id``).
            source_frame: frame the result maps from (its ``child_frame_id``).
            time: simulation time [s], or :data:`LATEST` (0) for the latest
                time common to the chain.

        Returns:
            The transform, stamped with the time used.

        Raises:
            FrameNotFoundError: a frame no transform has mentioned.
            ConnectivityError: the frames are in separate trees.
            ExtrapolationError: a dynamic link has no data at ``time``.
            InvalidArgumentError: ``time`` is not finite.
        """
        chain, used, a = self._resolve(target_frame, source_frame, time)
        return TransformStamped.from_rigid(chain.target, chain.source, used, a)

    def can_transform(self, target_frame: str, source_frame: str, time: float) -> bool:
        """Whether :meth:`lookup_transform` would succeed (False instead of raising,
        also for an empty frame name or a NaN time, as tf2's ``canTransform``)."""
        try:
            self._resolve(target_frame, source_frame, time)
        except TransformError:
            return False
        return True

    def transform_points(
        self, target_frame: str, source_frame: str, points: ArrayLike, time: float
    ) -> NDArray[np.float64]:
        """Map many points from ``source_frame`` into ``target_frame`` at once.

        Args:
            target_frame: frame to map into.
            source_frame: frame the points are in.
            points: (n, 3) points [m], or (n, 2) points taken at z = 0.
            time: simulation time [s], or :data:`LATEST`.

        Returns:
            (n, 3) or (n, 2) points in ``target_frame`` [m]; for (n, 2) input
            the mapped z is dropped (the ground projection, which for a
            yaw-only chain does not depend on the input z).

        Raises:
            The errors of :meth:`lookup_transform`, and InvalidArgumentError
            if ``points`` has another shape.
        """
        _, _, a = self._resolve(target_frame, source_frame, time)
        return transform_points_rigid(a, points)

    def lookup_pose2d(self, target_frame: str, source_frame: str, time: float) -> Pose2D:
        """The planar pose of ``source_frame``'s origin in ``target_frame``.

        x, y [m] and yaw [rad] in [-pi, pi) (Z-Y-X yaw); z, roll and pitch
        are dropped. Same arguments and errors as :meth:`lookup_transform`.
        """
        _, _, a = self._resolve(target_frame, source_frame, time)
        return Pose2D(a[0], a[1], float(wrap_angle(rigid.yaw_of(a))))

    def lookup_transform_full(
        self,
        target_frame: str,
        target_time: float,
        source_frame: str,
        source_time: float,
        fixed_frame: str,
    ) -> TransformStamped:
        """Map points in ``source_frame`` at ``source_time`` into ``target_frame`` at
        ``target_time``, through ``fixed_frame`` (tf2's "advanced" ``lookupTransform``).

        The result is ``(target_frame <- fixed_frame at target_time) ∘
        (fixed_frame <- source_frame at source_time)``: data stamped at one
        time, carried to another through a frame that does not move between
        the two (the world, ``reference``), e.g. the previous local path into
        the sensor frame of now. Each leg is :meth:`lookup_transform`, so
        :data:`LATEST` means the latest common time of that leg's own chain.
        A leg between a frame and itself (``fixed_frame`` is ``source_frame``
        or ``target_frame``) is the identity; at :data:`LATEST` it is stamped
        0, as :meth:`lookup_transform` of a frame in itself is here (tf2
        stamps it with the newest stamp of the frame's link to its parent).

        Args:
            target_frame: frame the result maps into (its ``frame_id``).
            target_time: time of ``target_frame`` [s], or :data:`LATEST`.
            source_frame: frame the result maps from (its ``child_frame_id``).
            source_time: time of ``source_frame`` [s], or :data:`LATEST`.
            fixed_frame: the frame both legs meet in, taken as unmoving.

        Returns:
            The transform, stamped with the time the target leg used
            (``target_time``, or its latest common time for :data:`LATEST`),
            as tf2's ``BufferCore`` stamps it.

        Raises:
            FrameNotFoundError: one of the three frames does not exist.
            InvalidArgumentError: an empty frame name or a non-finite time
                (all three frames and both times are checked before any leg).
            ConnectivityError: ``fixed_frame`` is not in the tree of
                ``source_frame`` or of ``target_frame``.
            ExtrapolationError: a dynamic link has no data at a leg's time;
                the message names the leg, its frames and its time.
        """
        target, source, used, a = self._resolve_full(
            target_frame, target_time, source_frame, source_time, fixed_frame
        )
        return TransformStamped.from_rigid(target, source, used, a)

    def can_transform_full(
        self,
        target_frame: str,
        target_time: float,
        source_frame: str,
        source_time: float,
        fixed_frame: str,
    ) -> bool:
        """Whether :meth:`lookup_transform_full` would succeed (False instead of raising)."""
        try:
            self._resolve_full(target_frame, target_time, source_frame, source_time, fixed_frame)
        except TransformError:
            return False
        return True

    def transform_points_full(  # noqa: PLR0917 (tf2's order, points as in transform_points)
        self,
        target_frame: str,
        target_time: float,
        source_frame: str,
        points: ArrayLike,
        source_time: float,
        fixed_frame: str,
    ) -> NDArray[np.float64]:
        """Map many points in ``source_frame`` at ``source_time`` into ``target_frame``
        at ``target_time``, through ``fixed_frame``.

        The arguments of :meth:`lookup_transform_full`, with ``points`` after
        ``source_frame`` as in :meth:`transform_points`: (n, 3) points [m], or
        (n, 2) points taken at z = 0, returned with the mapped z dropped.

        Raises:
            The errors of :meth:`lookup_transform_full`, and
            InvalidArgumentError if ``points`` has another shape.
        """
        _, _, _, a = self._resolve_full(
            target_frame, target_time, source_frame, source_time, fixed_frame
        )
        return transform_points_rigid(a, points)

    def latest_common_time(self, target_frame: str, source_frame: str) -> float:
        """The time a :data:`LATEST` lookup between the two frames would use [s]."""
        return self._chain(target_frame, source_frame).latest_common_time()

    def _resolve(
        self, target_frame: str, source_frame: str, time: float
    ) -> tuple[_Chain, float, Rigid]:
        """Find the chain, settle the time and compose: (chain, time used, transform)."""
        chain = self._chains.get((target_frame, source_frame))
        if chain is None:
            chain = self._chain(target_frame, source_frame)
        _check_time(time, "lookup time")
        if time == LATEST:
            time = chain.latest_common_time()
        try:
            a = _accumulate(chain.up_from_source, time)
            if chain.up_from_target:
                a = rigid.compose(rigid.invert(_accumulate(chain.up_from_target, time)), a)
        except ExtrapolationError as err:
            raise err.during_lookup(chain.target, chain.source) from None
        return chain, time, a

    def _resolve_full(
        self,
        target_frame: str,
        target_time: float,
        source_frame: str,
        source_time: float,
        fixed_frame: str,
    ) -> tuple[str, str, float, Rigid]:
        """Check the arguments, look up both legs and compose.

        Returns (target, source, the target leg's time, transform); the legs
        are looked up source first, as tf2 does.
        """
        method = "lookup_transform_full"
        target = self._known(target_frame, "target_frame", method)
        source = self._known(source_frame, "source_frame", method)
        fixed = self._known(fixed_frame, "fixed_frame", method)
        _check_time(target_time, "target_time")
        _check_time(source_time, "source_time")
        lookup: FullLookup = (target, target_time, source, source_time, fixed)
        _, fixed_from_source = self._leg("source", fixed_frame, source_frame, source_time, lookup)
        used, target_from_fixed = self._leg(
            "target", target_frame, fixed_frame, target_time, lookup
        )
        return target, source, used, rigid.compose(target_from_fixed, fixed_from_source)

    def _leg(
        self,
        leg: Literal["source", "target"],
        target_frame: str,
        source_frame: str,
        time: float,
        lookup: FullLookup,
    ) -> tuple[float, Rigid]:
        """One leg of a full lookup: (time used, transform); its errors name the leg."""
        try:
            _, used, a = self._resolve(target_frame, source_frame, time)
        except ExtrapolationError as err:
            raise err.with_context(full_lookup_context(leg, lookup)) from None
        except ConnectivityError as err:
            raise ConnectivityError(f"{err}, {full_lookup_context(leg, lookup)}") from None
        return used, a

    def _chain(self, target_frame: str, source_frame: str) -> _Chain:
        """Resolve (and remember) the links between two frames via their common ancestor."""
        cached = self._chains.get((target_frame, source_frame))
        if cached is not None:
            return cached
        target = self._known(target_frame, "target_frame")
        source = self._known(source_frame, "source_frame")
        source_path = self._path_to_root(source)
        depth = {frame: k for k, frame in enumerate(source_path)}
        up_from_target: list[FrameCache] = []
        frame = target
        while frame not in depth:
            link = self._links.get(frame)
            if link is None:
                raise ConnectivityError(
                    f"Could not find a connection between '{target}' and '{source}' because "
                    f"they are not part of the same tree: '{target}' is under root '{frame}', "
                    f"'{source}' under root '{source_path[-1]}'"
                )
            up_from_target.append(link)
            frame = link.parent
        up_from_source = tuple(self._links[f] for f in source_path[: depth[frame]])
        links = up_from_source + tuple(up_from_target)
        chain = _Chain(
            target=target,
            source=source,
            up_from_source=up_from_source,
            up_from_target=tuple(up_from_target),
            dynamic=tuple(link for link in links if isinstance(link, TimeCache)),
        )
        self._chains[(target_frame, source_frame)] = chain
        return chain

    def _known(self, frame_id: str, argument: str, method: str = "lookup_transform") -> str:
        """The stripped name of a frame that exists, else FrameNotFoundError."""
        frame = strip_leading_slash(frame_id)
        if not frame:
            raise InvalidArgumentError(f"{argument} must be a non-empty frame name")
        if frame not in self._frames:
            raise FrameNotFoundError(
                f"'{frame}' passed to {method} argument {argument} does not exist; "
                f"known frames: {sorted(self._frames)}"
            )
        return frame

    def _path_to_root(self, frame: str) -> list[str]:
        """``[frame, parent, grandparent, ..., root]``."""
        path = [frame]
        link = self._links.get(frame)
        while link is not None:
            path.append(link.parent)
            link = self._links.get(link.parent)
        return path

    # -- introspection -----------------------------------------------------------------------

    def frame_exists(self, frame_id: str) -> bool:
        """Whether any transform has named this frame (as parent or child)."""
        return strip_leading_slash(frame_id) in self._frames

    def all_frame_names(self) -> list[str]:
        """Every known frame name, sorted."""
        return sorted(self._frames)

    def frames(self) -> dict[str, FrameInfo]:
        """What is held for each frame that has a parent, keyed by frame name."""
        info: dict[str, FrameInfo] = {}
        for child, link in sorted(self._links.items()):
            if isinstance(link, TimeCache):
                oldest, latest = link.oldest, link.latest
            else:
                oldest = latest = link.stamp
            info[child] = FrameInfo(
                parent=link.parent,
                static=link.is_static,
                authority=self._authority[child],
                oldest=oldest,
                latest=latest,
                length=len(link),
            )
        return info
