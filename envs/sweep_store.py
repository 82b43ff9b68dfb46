"""A sweep's output directory: what is done, written the moment it is.

``DIR`` holds:

* ``sweep.json``: which sweep made it (its fingerprint, the axes, every
  run's id and labels), written before the first run;
* ``results.jsonl``: one row per finished run (``ROW_FIELDS``, the axes'
  labels, ``status`` ``ok`` or ``error``), appended, flushed and synced to
  disk as each run finishes, in the order they finish;
* ``runs/<run-id>/result.json`` and ``run.png`` (a run's own, as
  ``conesim run`` writes them, moved into place together), or
  ``runs/<run-id>/error.txt`` (the traceback of a run that raised).

A run's files are in place before its row is appended, so a row always has
its files; a sweep killed between the two runs that run again. Resuming
reads the rows (a last line cut short by a kill is dropped) and skips their
runs. ``DIR`` must be new, empty, or made by the same sweep (the same
fingerprint): the rules of ``envs.run_dir`` for one run, with a sweep's
marker.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TextIO

from conesim.envs.paths import nearest_existing, os_reason, probe_writable
from conesim.envs.run_dir import write_together
from conesim.envs.sweep_file import Sweep, SweepPoint

FORMAT = "conesim_sweep_dir"
"""``sweep.json``'s marker key (its value: the version, 1)."""
MANIFEST = "sweep.json"
RESULTS = "results.jsonl"
RUNS = "runs"
ROW_FIELDS = (
    "clean", "finished", "end_reason", "track", "seed", "sensors", "localization", "laps",
    "laps_completed", "best_lap_s", "lap_time_ratio", "cones_hit", "cones_down_or_out",
    "off_track_events", "localization_pos_rmse_m", "localization_yaw_rmse_deg",
    "midline_rmse_m", "planner_fallbacks", "sim_time_s", "wall_time_s", "setup_time_s",
)  # fmt: skip
"""The fields of a run's ``result.json`` that its row repeats."""


class SweepDirError(Exception):
    """``--out`` cannot take the sweep (one line: the path and why)."""


@dataclass(frozen=True)
class RunError:
    """A run that raised: the exception's type and message, and its traceback."""

    type: str
    message: str
    traceback: str


@dataclass(frozen=True)
class Outcome:
    """What a worker hands back for one run: the result, or the error.

    Attributes:
        payload: ``result.json``'s data (None after an error).
        picture: ``run.png``'s bytes (None after an error, or not drawn).
        error: what went wrong (None when the run finished).
    """

    payload: dict[str, Any] | None = None
    picture: bytes | None = None
    error: RunError | None = None


def manifest(sweep: Sweep) -> dict[str, Any]:
    """``sweep.json``'s data."""
    return {
        FORMAT: 1,
        "source": os.path.basename(sweep.source),
        "fingerprint": sweep.fingerprint,
        "axes": list(sweep.axes),
        "runs": [{"run_id": p.run_id, "labels": dict(p.labels)} for p in sweep.points],
    }


def read_manifest(out: Path) -> dict[str, Any] | None:
    """``out``'s ``sweep.json`` (None when it has none that conesim wrote)."""
    try:
        data = json.loads((out / MANIFEST).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) and data.get(FORMAT) == 1 else None


def check_sweep_dir(out: Path, sweep: Sweep) -> None:
    """Prove ``out`` may take the sweep and can be written, creating nothing.

    Raises:
        SweepDirError: the root directory, a file, a directory holding
            something else, or another sweep's directory.
    """
    try:
        full = Path(os.path.abspath(out))
        if full == Path(full.anchor):
            raise SweepDirError(f"{out}: is the root directory; give a directory for the sweep")
        base = nearest_existing(out)
        if not base.is_dir():
            where = "is not a directory" if base == out else f"{base} is not a directory"
            raise SweepDirError(f"{out}: {where}")
        if base == out and any(out.iterdir()):
            made = read_manifest(out)
            if made is None:
                what = (
                    "a sweep.json conesim cannot read (damaged, or not its own)"
                    if (out / MANIFEST).exists()
                    else "other files and no sweep.json"
                )
                raise SweepDirError(f"{out}: holds {what}; give a new or empty directory")
            if made.get("fingerprint") != sweep.fingerprint:
                raise SweepDirError(
                    f"{out}: holds a sweep of other runs (from {made.get('source')}); "
                    "give a new directory, or the sweep file that made it"
                )
        probe_writable(base)
    except OSError as exc:
        raise SweepDirError(f"{out}: cannot write there ({os_reason(exc)})") from None


def read_rows(path: Path) -> list[dict[str, Any]]:
    """The rows of a ``results.jsonl`` (a last line cut short is dropped; later rows of
    the same run replace earlier ones)."""
    rows: dict[str, dict[str, Any]] = {}
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        return []
    for line in text.splitlines():
        try:
            row = json.loads(line)
        except ValueError:
            continue
        if isinstance(row, dict) and isinstance(row.get("run_id"), str):
            rows[row["run_id"]] = row
    return list(rows.values())


def make_row(point: SweepPoint, outcome: Outcome) -> dict[str, Any]:
    """The results table's row of a run."""
    row: dict[str, Any] = {"run_id": point.run_id, "index": point.index}
    row["axes"] = dict(point.labels)
    if outcome.error is not None:
        row.update(status="error", clean=False)
        row["error"] = {"type": outcome.error.type, "message": outcome.error.message}
        return row
    assert outcome.payload is not None
    row["status"] = "ok"
    row.update({key: outcome.payload[key] for key in ROW_FIELDS})
    return row


class SweepStore:
    """Writes a sweep's outputs into its directory (see the module docstring)."""

    def __init__(self, out: Path, sweep: Sweep) -> None:
        self.out = out
        self.sweep = sweep
        self._results: TextIO | None = None

    def open(self) -> list[dict[str, Any]]:
        """Make the directory, write ``sweep.json``, and return the rows already there."""
        (self.out / RUNS).mkdir(parents=True, exist_ok=True)
        if read_manifest(self.out) is None:
            payload = json.dumps(manifest(self.sweep), indent=1) + "\n"
            write_together(self.out, {MANIFEST: lambda p: p.write_text(payload, encoding="utf-8")})
        path = self.out / RESULTS
        _drop_cut_line(path)
        ids = {p.run_id for p in self.sweep.points}
        rows = [row for row in read_rows(path) if row["run_id"] in ids]
        self._results = path.open("a", encoding="utf-8")
        return rows

    def record(self, point: SweepPoint, outcome: Outcome) -> dict[str, Any]:
        """Write a finished run's files, then append its row (synced); the row."""
        assert self._results is not None, "open() first"
        folder = self.out / RUNS / point.run_id
        if outcome.error is not None:
            text = outcome.error.traceback
            write_together(folder, {"error.txt": lambda p: p.write_text(text, encoding="utf-8")})
        else:
            payload = json.dumps(outcome.payload, indent=2) + "\n"
            picture = outcome.picture
            files: dict[str, Callable[[Path], object]] = {}
            if picture is not None:
                files["run.png"] = lambda p: p.write_bytes(picture)
            files["result.json"] = lambda p: p.write_text(payload, encoding="utf-8")
            write_together(folder, files)
        row = make_row(point, outcome)
        self._results.write(json.dumps(row) + "\n")
        self._results.flush()
        os.fsync(self._results.fileno())
        return row

    def close(self) -> None:
        """Close the results table."""
        if self._results is not None:
            self._results.close()
            self._results = None

    def __enter__(self) -> SweepStore:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _drop_cut_line(path: Path) -> None:
    """Cut a last line that a kill left without its newline (the next row starts clean)."""
    try:
        with path.open("rb+") as stream:
            data = stream.read()
            if data and not data.endswith(b"\n"):
                stream.truncate(data.rfind(b"\n") + 1)
    except FileNotFoundError:
        pass


def pending(sweep: Sweep, rows: Sequence[Mapping[str, Any]]) -> Iterator[SweepPoint]:
    """The sweep's runs that have no row yet, in order."""
    done = {row["run_id"] for row in rows}
    return (p for p in sweep.points if p.run_id not in done)
