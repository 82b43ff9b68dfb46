"""What a reader extracts from a file, before it becomes a `Track`."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from conesim.core.pose import Pose2D
from conesim.tracks.kinds import ConeKind, Layout


@dataclass(frozen=True)
class RawCone:
    """One cone as read.

    Attributes:
        x: east [m].
        y: north [m].
        kind: its colour.
        line: 1-based line in the file, for messages.
    """

    x: float
    y: float
    kind: ConeKind
    line: int


@dataclass
class RawTrack:
    """A track file's content.

    Attributes:
        cones: every cone, in file order.
        start_pose: the start pose, or None if the file has none.
        layout: the layout if the format states it, else None (detected).
        name: the track name if the format states it, else None (file stem).
        description: free text.
        global_path_file: the global path CSV named by the file, if any.
    """

    cones: list[RawCone] = field(default_factory=list)
    start_pose: Pose2D | None = None
    layout: Layout | None = None
    name: str | None = None
    description: str = ""
    global_path_file: Path | None = None
