"""Output paths: where a result may be written, before anything is.

``conesim run`` writes its outputs (``--out``'s pair, ``--bag``'s directory)
only once the run is over, and checks before the run that they can be: the
nearest existing ancestor of the target must be a writable directory (a
probe file is created there and removed), and the directories that do not
exist yet are created at the end, and removed again if the write fails.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path


def nearest_existing(path: Path) -> Path:
    """``path`` itself if it exists, else its nearest existing ancestor."""
    while not path.exists() and path != path.parent:
        path = path.parent
    return path


def missing_dirs(path: Path) -> list[Path]:
    """The directories ``path.mkdir(parents=True)`` would create, outermost first."""
    base = nearest_existing(path)
    missing = []
    while path != base:
        missing.append(path)
        path = path.parent
    return missing[::-1]


def probe_writable(directory: Path) -> None:
    """Create and remove a file in ``directory``.

    Raises:
        OSError: the directory cannot be written (or is not one).
    """
    fd, probe = tempfile.mkstemp(prefix=".conesim-write-test-", dir=directory)
    os.close(fd)
    os.unlink(probe)


def os_reason(exc: OSError) -> str:
    """An OSError's reason without the (possibly temporary) file name."""
    return exc.strerror or type(exc).__name__
