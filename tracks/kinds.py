"""Cone kinds and track layouts (REFERENCES.md, "Formula Student tracks")."""

from __future__ import annotations

from enum import StrEnum


class ConeKind(StrEnum):
    """Cone colours as Formula Student uses them.

    Blue cones mark the left boundary and yellow the right one (in the driving
    direction); small orange cones mark braking zones and lanes; big orange
    cones stand at the start/finish (timing) lines.
    """

    BLUE = "blue"
    YELLOW = "yellow"
    ORANGE = "orange"
    BIG_ORANGE = "big_orange"
    UNKNOWN = "unknown"


CONE_KINDS: tuple[ConeKind, ...] = tuple(ConeKind)
"""Every kind, in the canonical order in which a `Track` stores its cones."""


class Layout(StrEnum):
    """The shape of a track.

    ``closed``: a loop (trackdrive, autocross); ``open``: a lane driven once
    from start to end (acceleration); ``skidpad``: the FS figure of eight.
    """

    CLOSED = "closed"
    OPEN = "open"
    SKIDPAD = "skidpad"
