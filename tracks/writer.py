"""Writing a track in our own YAML format, atomically.

Floats are written with Python's shortest round-tripping repr, so reading the
file back reproduces the track exactly (`Track.__eq__`).
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Any

import yaml

from tracks.kinds import CONE_KINDS
from tracks.model import Track
from tracks.readers_yaml import FORMAT_VERSION


def track_document(track: Track, directory: Path | None = None) -> dict[str, Any]:
    """The track as our format's YAML document (a plain dict).

    Args:
        track: the track.
        directory: where the file will live; the global path is written
            relative to it (default: the global path's own directory).
    """
    global_path = None
    if track.global_path_file is not None:
        base = directory if directory is not None else track.global_path_file.parent
        global_path = Path(os.path.relpath(track.global_path_file, base)).as_posix()
    pose = track.start_pose
    doc: dict[str, Any] = {
        "conesim_track": FORMAT_VERSION,
        "name": track.name,
    }
    if track.description:
        doc["description"] = track.description
    doc["layout"] = str(track.layout)
    doc["start_pose"] = [float(pose.x), float(pose.y), float(pose.yaw)]
    doc["global_path"] = global_path
    doc["cones"] = {
        str(kind): [[float(x), float(y)] for x, y in track.cones_of(kind)]
        for kind in CONE_KINDS
        if any(k == kind for k in track.kinds)
    }
    return doc


def _file_mode() -> int:
    """The mode a plain ``open()`` would give a new file: 0666 minus the umask."""
    mask = os.umask(0o022)
    os.umask(mask)
    return 0o666 & ~mask


def write_track(track: Track, path: str | os.PathLike[str]) -> Path:
    """Write ``track`` to ``path`` in our own format.

    The file appears complete or not at all: it is written to a temporary
    file in the same directory and moved into place with ``os.replace``.

    Returns:
        The path written.
    """
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    text = yaml.safe_dump(
        track_document(track, target.parent.resolve()),
        sort_keys=False,
        default_flow_style=None,
        allow_unicode=True,
        width=100,
    )
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as handle:
            handle.write(text)
        os.chmod(tmp, _file_mode())  # mkstemp creates 0600; a track file is for everyone
        os.replace(tmp, target)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return target
