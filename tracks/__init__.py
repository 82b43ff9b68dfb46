"""Cone tracks: the `Track` type, readers and writer, validator, shipped tracks.

The bottom layer of conesim: it imports numpy, scipy, yaml and the leaf
module ``localization.pose`` only.

>>> from tracks import load_track, check_report
>>> track = load_track("trackdrive")          # a shipped track, or a file path
>>> report = check_report(track)              # FS rules as warnings, errors
"""

from __future__ import annotations

import logging

from tracks.derived import SkidpadCircle, TrackGeometry
from tracks.errors import TrackFormatError, TrackGeometryError, TrackNotFoundError
from tracks.geometry import derive_start_pose, detect_layout
from tracks.kinds import ConeKind, Layout
from tracks.model import Track
from tracks.readers import TrackFileFormat, detect_format, read_track
from tracks.shipped import DEFAULT_TRACK, load_track, shipped_track_path, shipped_tracks
from tracks.validate import ValidationReport, check_report, validate_track
from tracks.writer import write_track

__all__ = [
    "DEFAULT_TRACK",
    "ConeKind",
    "Layout",
    "SkidpadCircle",
    "Track",
    "TrackFileFormat",
    "TrackFormatError",
    "TrackGeometry",
    "TrackGeometryError",
    "TrackNotFoundError",
    "ValidationReport",
    "check_report",
    "derive_start_pose",
    "detect_format",
    "detect_layout",
    "load_track",
    "read_track",
    "shipped_track_path",
    "shipped_tracks",
    "validate_track",
    "write_track",
]

# A library logs, the application shows (see ``localization/__init__``).
logging.getLogger(__name__).addHandler(logging.NullHandler())
