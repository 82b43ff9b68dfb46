"""The tracks shipped in ``tracks/data`` and ``load_track`` by name or path.

The data files are found through ``importlib.resources``, so they are found
from a source checkout, an editable install and a plain ``pip install .``
alike (pyproject.toml declares ``tracks/data/*.yaml`` and ``*.csv`` as
package data).
"""

from __future__ import annotations

import atexit
import os
from contextlib import ExitStack
from functools import cache
from importlib.resources import as_file, files
from pathlib import Path

from conesim.tracks.errors import TrackNotFoundError
from conesim.tracks.generate import GeneratedTrack, generate_track
from conesim.tracks.model import Track
from conesim.tracks.readers import read_track

DEFAULT_TRACK = "trackdrive"
"""The track used when none is named: a gentle FS trackdrive-style loop."""

_DATA = "data"
_SUFFIX = ".yaml"
_extracted = ExitStack()  # for installs where the data is not a plain directory (zip)
atexit.register(_extracted.close)


def shipped_tracks() -> list[str]:
    """Names of the shipped tracks, sorted."""
    data = files("conesim.tracks").joinpath(_DATA)
    if not data.is_dir():
        return []
    return sorted(
        entry.name[: -len(_SUFFIX)]
        for entry in data.iterdir()
        if entry.name.endswith(_SUFFIX) and entry.is_file()
    )


_extraction: list[Path] = []  # where a zipped install's data was extracted, once


def shipped_data_dir() -> Path:
    """The directory holding the shipped track files (extracted once for a zipped install)."""
    data = files("conesim.tracks").joinpath(_DATA)
    if isinstance(data, Path):
        return data
    if not _extraction:
        _extraction.append(_extracted.enter_context(as_file(data)))
    return _extraction[0]


def is_shipped_file(path: Path) -> bool:
    """Whether ``path`` is one of the shipped data files (nothing is extracted to tell)."""
    data = files("conesim.tracks").joinpath(_DATA)
    base = data if isinstance(data, Path) else (_extraction[0] if _extraction else None)
    return base is not None and path.resolve().is_relative_to(base.resolve())


def shipped_track_path(name: str) -> Path:
    """The file of the shipped track ``name``.

    Raises:
        TrackNotFoundError: no shipped track of that name (the message lists them).
    """
    names = shipped_tracks()
    if name not in names:
        raise TrackNotFoundError(
            f"unknown track {name!r}; shipped tracks: {', '.join(names) or '(none)'}"
        )
    # A zipped install extracts the whole data directory, so that the global
    # path CSV sits next to the track.
    return shipped_data_dir() / (name + _SUFFIX)


TrackSource = str | os.PathLike[str] | GeneratedTrack
"""What names a track: a shipped track's name, a track file, or a generated track."""


def load_track(name_or_path: TrackSource) -> Track:
    """A shipped track by name (e.g. ``"autocross"``), a track file by path, or a
    generated track (``GeneratedTrack(seed, spec)``).

    A string that is a shipped track's name loads that track; anything else
    is read as a file path (any supported format, see `read_track`).

    Raises:
        TrackGenerationError: a generated track that cannot be made.
        TrackFormatError: the file is not a valid track. Its subclass
            TrackNotFoundError: neither a shipped name nor an existing file
            (the message lists the shipped names).
    """
    if isinstance(name_or_path, GeneratedTrack):
        return _generated(name_or_path)
    if isinstance(name_or_path, str) and name_or_path in shipped_tracks():
        return _load_shipped(name_or_path)
    path = Path(name_or_path)
    if not path.exists():
        names = ", ".join(shipped_tracks()) or "(none)"
        raise TrackNotFoundError(
            f"{os.fspath(name_or_path)!r} is neither a shipped track ({names}) nor an existing file"
        )
    return read_track(path)


@cache
def _load_shipped(name: str) -> Track:
    """Shipped tracks are immutable data: read and derive each once per process."""
    return read_track(shipped_track_path(name))


@cache
def _generated(recipe: GeneratedTrack) -> Track:
    """Generated tracks are deterministic: make each once per process."""
    return generate_track(recipe.seed, recipe.spec)


def track_label(source: TrackSource) -> str:
    """How messages name a track: its name, its file, or the generated track's name."""
    if isinstance(source, GeneratedTrack):
        return source.name
    return os.fspath(source)
