"""Helpers of the sweep tests."""

from __future__ import annotations

import shutil
from pathlib import Path

from conesim.tracks.shipped import shipped_track_path


def copy_track(name: str, to: Path) -> Path:
    """A shipped track's file (and its global path beside it) copied to ``to``."""
    source = shipped_track_path(name)
    for extra in source.parent.glob(f"{name}_*"):
        shutil.copy(extra, to.parent / extra.name)
    shutil.copy(source, to)
    return to
