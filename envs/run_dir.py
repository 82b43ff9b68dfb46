"""Where ``conesim run`` may write its outputs: the ``--out`` directory's rules.

A run writes two files, ``result.json`` and ``run.png``, replacing a
previous run's. So that a slip of the keyboard cannot scatter them over
something else (``--out /``, ``--out ~``, ``--out .`` in a source tree), the
directory must be one of:

* new (it and any missing parents are made when the run is over);
* empty;
* a previous run's: it holds a ``result.json`` that conesim wrote (a JSON
  object with ``track`` and ``end_reason``); whatever else is in it (notes,
  a bag, the scenario file) is the user's and stays;
* one that holds nothing but the scenario file being run (a run's folder
  made for it).

Refused, before any simulation: the root directory, a file, a directory
with other content, an output name that is a directory, a place that
cannot be written, and the same directory as ``--bag`` (or one inside it:
the bag's directory must be new or empty, and is the bag's alone).
"""

from __future__ import annotations

import contextlib
import json
import os
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path

from conesim.envs.paths import missing_dirs, nearest_existing, os_reason, probe_writable

OUTPUT_FILES = ("run.png", "result.json")  # the order they are moved into place
_RESULT_KEYS = ("track", "end_reason")  # a result.json that conesim wrote has these
_MAX_RESULT_BYTES = 1 << 22  # [B] a result.json is a few kB


class RunDirError(Exception):
    """``--out`` cannot take the run's outputs (one line: the path and why)."""


def is_previous_run(directory: Path) -> bool:
    """Whether ``directory`` holds a ``result.json`` that conesim wrote."""
    result = directory / "result.json"
    try:
        if not result.is_file() or result.stat().st_size > _MAX_RESULT_BYTES:
            return False
        data = json.loads(result.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return False
    return isinstance(data, dict) and all(key in data for key in _RESULT_KEYS)


def _is_ours(entry: Path) -> bool:
    """A temporary name of the outputs' own (an interrupted write leaves one)."""
    return entry.name.endswith(".tmp") and entry.name.startswith(
        tuple(f".{name}." for name in OUTPUT_FILES)
    )


def check_run_dir(out: Path, *, scenario: Path | None = None, bag: Path | None = None) -> None:
    """Prove ``out`` may take the outputs and can be written, creating nothing.

    Args:
        out: the ``--out`` directory.
        scenario: the scenario file being run, which may sit in ``out``.
        bag: the ``--bag`` directory, if any.

    Raises:
        RunDirError: see the module docstring for what is refused.
    """
    try:
        full = Path(os.path.abspath(out))
        if full == Path(full.anchor):
            raise RunDirError(f"{out}: is the root directory; give a directory for the run")
        if bag is not None:
            bag_full = Path(os.path.abspath(bag))
            if full == bag_full or bag_full in full.parents:
                raise RunDirError(f"{out}: is --bag's directory or inside it; give each its own")
        base = nearest_existing(out)
        if not base.is_dir():
            where = "is not a directory" if base == out else f"{base} is not a directory"
            raise RunDirError(f"{out}: {where}")
        if base == out:
            _check_contents(out, scenario)
        probe_writable(base)
    except OSError as exc:
        raise RunDirError(f"{out}: cannot write there ({os_reason(exc)})") from None


def _check_contents(out: Path, scenario: Path | None) -> None:
    """An existing ``out``: empty, a previous run's, or the scenario's own folder."""
    for name in OUTPUT_FILES:
        if (out / name).is_dir():
            raise RunDirError(f"{out}: {out / name} is a directory, not a file")
    keep = None if scenario is None else os.path.abspath(scenario)
    others = sorted(
        entry.name
        for entry in out.iterdir()
        if entry.name not in OUTPUT_FILES and not _is_ours(entry) and os.path.abspath(entry) != keep
    )
    if others and not is_previous_run(out):
        shown = ", ".join(others[:3]) + (", ..." if len(others) > 3 else "")
        raise RunDirError(
            f"{out}: holds other files ({shown}) and no previous run's result.json; "
            "give a new or empty directory"
        )


def write_together(out: Path, writers: Mapping[str, Callable[[Path], object]]) -> None:
    """Write files into ``out`` (made if missing): all of them, or none.

    ``writers`` maps each file's name to a function that writes it to the
    path it is given. Each goes to a temporary name first; they are moved
    into place, in order, only when all were written. Files of the same
    names already there are first moved aside and put back if a move fails,
    so ``out`` holds the new set or the old one, never a mix; directories
    this call created are removed on any failure. One writer per directory
    at a time: two writing the same ``out`` at once may interleave their moves.

    Raises:
        OSError: a file could not be written or moved (nothing is left of it).
    """
    created = missing_dirs(out)
    tag = f"{os.getpid()}.tmp"
    tmp = {name: out / f".{name}.{tag}" for name in writers}
    old = {name: out / f".{name}.old.{tag}" for name in writers}
    aside: list[str] = []
    moved: list[Path] = []
    try:
        out.mkdir(parents=True, exist_ok=True)
        for name, write in writers.items():
            write(tmp[name])
        for name in writers:
            if (out / name).exists():
                os.replace(out / name, old[name])
                aside.append(name)
        for name in writers:
            os.replace(tmp[name], out / name)
            moved.append(out / name)
    except OSError:
        for path in moved:
            path.unlink(missing_ok=True)
        for name in aside:
            with contextlib.suppress(OSError):
                os.replace(old[name], out / name)
        _remove(tmp.values())
        for directory in reversed(created):
            with contextlib.suppress(OSError):
                directory.rmdir()
        raise
    _remove([*tmp.values(), *old.values()])


def _remove(paths: Iterable[Path]) -> None:
    for path in paths:
        with contextlib.suppress(OSError):
            path.unlink(missing_ok=True)
