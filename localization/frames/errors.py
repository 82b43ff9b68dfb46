"""Exceptions raised by the frame tree.

The hierarchy follows tf2's exceptions (ros2/geometry2 ``tf2/exceptions.hpp``):
``LookupException``, ``ConnectivityException``, ``ExtrapolationException`` and
``InvalidArgumentException``, under one base class, so that a caller can catch
"any frame-tree failure" with :class:`TransformError`. tf2 only logs and drops
a bad ``setTransform`` input (``TF_SELF_TRANSFORM``, ``TF_NAN_INPUT``,
``TF_DENORMALIZED_QUATERNION``); here it raises :class:`InvalidTransformError`
instead, and :class:`FrameTreeError` for the tree rules that tf2 does not have
(one parent per frame, no cycles).

Every message names the frames and, for extrapolation, the requested time and
the time range the buffer holds.
"""

from __future__ import annotations

from typing import Literal, TypeAlias

Direction = Literal["past", "future"]


class TransformError(Exception):
    """Base class of every frame-tree error."""


class FrameNotFoundError(TransformError, LookupError):
    """A frame name that no transform has mentioned (tf2 ``LookupException``)."""


class ConnectivityError(TransformError):
    """The two frames are in separate trees (tf2 ``ConnectivityException``)."""


class InvalidArgumentError(TransformError, ValueError):
    """A query argument is malformed: empty frame name, non-finite time, bad shape.

    tf2 raises ``InvalidArgumentException`` for the same kind of misuse.
    """


class InvalidTransformError(TransformError, ValueError):
    """A transform that may not enter the buffer.

    Self-transforms, empty frame names, NaN or infinite values, a quaternion
    that is not unit-norm, or arrays of the wrong shape.
    """


class FrameTreeError(InvalidTransformError):
    """A transform that would give a frame a second parent or close a cycle."""


class ExtrapolationError(TransformError):
    """The requested time lies outside the data held for one link of the chain.

    Attributes:
        frame: child frame of the link that has no data at ``time``.
        parent: parent frame of that link.
        time: requested time [s].
        earliest: oldest stamp held for the link [s].
        latest: newest stamp held for the link [s].
        direction: ``"past"`` if ``time < earliest``, else ``"future"``.
    """

    def __init__(
        self,
        frame: str,
        parent: str,
        time: float,
        earliest: float,
        latest: float,
        *,
        context: str = "",
    ) -> None:
        self.frame = frame
        self.parent = parent
        self.time = time
        self.earliest = earliest
        self.latest = latest
        self.direction: Direction = "past" if time < earliest else "future"
        self.context = context
        super().__init__(self._message())

    def _message(self) -> str:
        if self.earliest == self.latest:
            held = f"only time {self.latest!r} s is in the buffer"
        elif self.direction == "past":
            held = f"the earliest data is at time {self.earliest!r} s"
        else:
            held = f"the latest data is at time {self.latest!r} s"
        message = (
            f"Lookup would require extrapolation into the {self.direction}: requested time "
            f"{self.time!r} s but {held} for '{self.parent}' -> '{self.frame}' "
            f"(available [{self.earliest!r}, {self.latest!r}] s)"
        )
        return f"{message}, {self.context}" if self.context else message

    def during_lookup(self, target_frame: str, source_frame: str) -> ExtrapolationError:
        """The same error, with the lookup that ran into it added to the message."""
        return self.with_context(
            f"when looking up transform from frame '{source_frame}' to frame '{target_frame}'"
        )

    def with_context(self, context: str) -> ExtrapolationError:
        """The same error with ``context`` (the lookup it happened in) in place of its own."""
        return ExtrapolationError(
            self.frame, self.parent, self.time, self.earliest, self.latest, context=context
        )


FullLookup: TypeAlias = tuple[str, float, str, float, str]
"""A full lookup's arguments (target_frame, target_time, source_frame, source_time, fixed_frame)."""


def full_lookup_context(leg: Literal["source", "target"], lookup: FullLookup) -> str:
    """Which leg of a full (time-travel) lookup failed, and the lookup, for an error message.

    The source leg maps ``source_frame`` at ``source_time`` into
    ``fixed_frame``; the target leg maps ``fixed_frame`` into ``target_frame``
    at ``target_time``. A time of 0 is shown as the latest common time it stands for.
    """
    target_frame, target_time, source_frame, source_time, fixed_frame = lookup

    def at(time: float) -> str:
        return f"{time!r} s (latest)" if time == 0.0 else f"{time!r} s"

    if leg == "source":
        step = (
            f"the source leg, frame '{source_frame}' at source_time {at(source_time)} "
            f"into fixed frame '{fixed_frame}'"
        )
    else:
        step = (
            f"the target leg, fixed frame '{fixed_frame}' into frame '{target_frame}' "
            f"at target_time {at(target_time)}"
        )
    return (
        f"in {step}, when looking up transform from frame '{source_frame}' at time "
        f"{at(source_time)} to frame '{target_frame}' at time {at(target_time)} "
        f"through fixed frame '{fixed_frame}'"
    )
