"""The one exception family of the tracks package.

Every problem with a track file or a track's geometry raises
:class:`TrackFormatError` (a ``ValueError``), whose message names the file,
the line where there is one, and what is wrong::

    track.csv:12: column 'x': 'abc' is not a number
"""

from __future__ import annotations

import os


class TrackFormatError(ValueError):
    """A track file or track definition that cannot be used.

    Args:
        message: what is wrong.
        path: the file, if the track came from one.
        line: the 1-based line in ``path`` where the problem is, if known.
    """

    def __init__(
        self, message: str, path: str | os.PathLike[str] | None = None, line: int | None = None
    ) -> None:
        self.path = None if path is None else os.fspath(path)
        self.line = line
        self.reason = message
        where = ""
        if self.path is not None:
            where = f"{self.path}:{line}: " if line is not None else f"{self.path}: "
        super().__init__(f"{where}{message}")

    def __reduce__(self) -> tuple[type[TrackFormatError], tuple[str, str | None, int | None]]:
        return type(self), (self.reason, self.path, self.line)

    def with_path(self, path: str | os.PathLike[str]) -> TrackFormatError:
        """The same error, attributed to ``path`` if it names no file yet."""
        if self.path is not None:
            return self
        return type(self)(self.reason, path, self.line)


class TrackGeometryError(TrackFormatError):
    """Cones from which no centreline, boundaries or start line can be derived."""


class TrackNotFoundError(TrackFormatError):
    """Neither a shipped track name nor an existing file."""
