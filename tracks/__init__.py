"""Cone tracks: the `Track` type, readers and writer, validator, global path, shipped tracks.

The lowest layer above ``conesim.core``: it imports numpy, scipy, yaml and
``conesim.core`` only.

>>> from conesim.tracks import load_track, check_report
>>> track = load_track("trackdrive")          # a shipped track, or a file path
>>> report = check_report(track)              # FS rules as warnings, errors
"""

from __future__ import annotations

from conesim.tracks.derived import SkidpadCircle, TrackGeometry
from conesim.tracks.errors import TrackFormatError, TrackGeometryError, TrackNotFoundError
from conesim.tracks.generate import GeneratedTrack, TrackGenerationError, TrackSpec, generate_track
from conesim.tracks.geometry import derive_start_pose, detect_layout
from conesim.tracks.kinds import ConeKind, Layout
from conesim.tracks.model import Track
from conesim.tracks.readers import TrackFileFormat, detect_format, read_track
from conesim.tracks.shipped import (
    DEFAULT_TRACK,
    TrackSource,
    load_track,
    shipped_track_path,
    shipped_tracks,
    track_label,
)
from conesim.tracks.validate import ValidationReport, check_report, validate_track
from conesim.tracks.writer import write_track

__all__ = [
    "DEFAULT_TRACK",
    "ConeKind",
    "GeneratedTrack",
    "Layout",
    "SkidpadCircle",
    "Track",
    "TrackFileFormat",
    "TrackFormatError",
    "TrackGenerationError",
    "TrackGeometry",
    "TrackGeometryError",
    "TrackNotFoundError",
    "TrackSource",
    "TrackSpec",
    "ValidationReport",
    "check_report",
    "derive_start_pose",
    "detect_format",
    "detect_layout",
    "generate_track",
    "load_track",
    "read_track",
    "shipped_track_path",
    "shipped_tracks",
    "track_label",
    "validate_track",
    "write_track",
]
