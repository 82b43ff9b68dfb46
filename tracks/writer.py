"""Writing a track in our own YAML format, atomically.

Floats are written with Python's shortest round-tripping repr, so reading the
file back reproduces the track exactly (`Track.__eq__`).

The global path is written as a path relative to the track file. A shipped
track's global path lives in the installed package (``site-packages``, or a
temporary extraction of a zipped install), where a link would break when the
environment moves or the file is shared: written anywhere else, such a track
gets a copy of its global path CSV next to it (``<stem>_path.csv``).
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Any

import yaml

from conesim.tracks.kinds import CONE_KINDS
from conesim.tracks.model import Track
from conesim.tracks.readers_yaml import FORMAT_VERSION
from conesim.tracks.shipped import is_shipped_file


def track_document(
    track: Track, directory: Path | None = None, global_path_file: Path | None = None
) -> dict[str, Any]:
    """The track as our format's YAML document (a plain dict).

    Args:
        track: the track.
        directory: where the file will live; the global path is written
            relative to it (default: the global path's own directory).
        global_path_file: the global path CSV to name instead of the track's.
    """
    global_path = None
    csv = global_path_file if global_path_file is not None else track.global_path_file
    if csv is not None:
        base = directory if directory is not None else csv.parent
        global_path = Path(os.path.relpath(csv, base)).as_posix()
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
    file in the same directory and moved into place with ``os.replace``. A
    shipped track's global path is first copied next to it, byte for byte
    (module docstring); if the track then cannot be written, the copy is
    removed again, or the file it replaced put back.

    Returns:
        The path written.

    Raises:
        FileExistsError: the copy would replace another file (one that is
            not the global path of the track file being replaced); checked
            before anything is created.
    """
    target = Path(path)
    csv, shipped = _global_path_plan(track, target)
    target.parent.mkdir(parents=True, exist_ok=True)
    text = yaml.safe_dump(
        track_document(track, target.parent.resolve(), csv),
        sort_keys=False,
        default_flow_style=None,
        allow_unicode=True,
        width=100,
    )
    replaced = None
    if shipped is not None and csv is not None:
        replaced = csv.read_bytes() if csv.exists() else None
        _write_atomically(csv, shipped.read_bytes())
    try:
        _write_atomically(target, text.encode("utf-8"))
    except BaseException:
        if shipped is not None and csv is not None:
            if replaced is None:
                csv.unlink(missing_ok=True)
            else:
                _write_atomically(csv, replaced)
        raise
    return target


def _global_path_plan(track: Track, target: Path) -> tuple[Path | None, Path | None]:
    """The global path CSV the written track names, and the shipped file to copy there first.

    A shipped global path outside ``target``'s directory is copied there as
    ``<stem>_path.csv``: not when an identical file is already there, and
    over a different one only when that is the global path the track file
    being replaced names. Any other global path is named where it is.
    """
    source = track.global_path_file
    if source is None or not is_shipped_file(source):
        return source, None
    directory = target.parent.resolve()
    if source.resolve().parent == directory:
        return source, None
    copy = directory / f"{target.stem}_path.csv"
    if copy.exists():
        if copy.read_bytes() == source.read_bytes():
            return copy, None
        if not _names_global_path(target, copy.name):
            raise FileExistsError(
                f"{copy}: exists and is not the global path of {track.name!r}; "
                "remove it or write the track elsewhere"
            )
    return copy, source


def _names_global_path(track_file: Path, name: str) -> bool:
    """Whether ``track_file`` is a conesim track whose global path is ``name`` beside it."""
    try:
        doc = yaml.safe_load(track_file.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, yaml.YAMLError):
        return False
    return isinstance(doc, dict) and "conesim_track" in doc and doc.get("global_path") == name


def _write_atomically(target: Path, data: bytes) -> None:
    """Write ``data`` to a temporary file beside ``target``, then move it into place."""
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    try:
        with os.fdopen(fd, "wb") as handle:
            handle.write(data)
        os.chmod(tmp, _file_mode())  # mkstemp creates 0600; track files are for everyone
        os.replace(tmp, target)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
