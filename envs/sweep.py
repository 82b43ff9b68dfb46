"""Sweeps: many runs of a scenario, varied along axes, written as they finish.

``run_sweep`` is what ``conesim sweep`` calls: a loaded sweep file
(``envs.sweep_file``), an output directory (``envs.sweep_store``), and
where the runs run (``envs.sweep_workers``). Each run's row and files are
written the moment it finishes; the runs already in the directory are
skipped, so the same call after an interrupted one resumes it; a run that
raises is recorded as an ``error`` row and the others go on. At the end the
summary is written (``envs.sweep_summary``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TextIO

from conesim.envs.progress import SweepProgress
from conesim.envs.sweep_file import Sweep
from conesim.envs.sweep_store import SweepStore, check_sweep_dir, pending
from conesim.envs.sweep_summary import write_summary
from conesim.envs.sweep_workers import (
    Pictures,
    Results,
    default_workers,
    pool,
    ray_tasks,
    serial,
)

LOCAL_RAY = "local"
"""``ray=LOCAL_RAY``: start a local Ray (``--ray`` without an address)."""


@dataclass(frozen=True)
class SweepReport:
    """How a sweep went: its runs, those skipped (already done), run now, clean, errors."""

    total: int
    skipped: int
    ran: int
    clean: int
    errors: int
    summary: str


def run_sweep(
    sweep: Sweep,
    out: Path,
    *,
    workers: int | None = None,
    ray: str | None = None,
    pictures: Pictures = "all",
    stderr: TextIO | None = None,
    tty: bool = False,
    on_row: Callable[[dict[str, Any]], None] | None = None,
) -> SweepReport:
    """Run the sweep's runs that ``out`` does not hold yet; write the summary.

    Args:
        sweep: the runs.
        out: the output directory (new, empty, or this sweep's).
        workers: processes (None: every core); 1 runs in this process.
            With ``ray``: the local Ray's CPUs, one actor each (on a cluster: one
            actor per CPU of the cluster).
        ray: None (local processes), ``LOCAL_RAY`` (a local Ray), or a
            Ray cluster's address.
        pictures: which runs get a ``run.png``: ``all``, ``failed`` (not
            clean) or ``none``.
        stderr: where the progress goes (None: nowhere).
        tty: ``stderr`` is a terminal (a bar, not sparse lines).
        on_row: called with each row once it is written (``results.jsonl``).

    Raises:
        SweepDirError: ``out`` cannot take the sweep (nothing written).
        gymnasium.error.DependencyNotInstalled: ``ray`` without Ray installed.
    """
    check_sweep_dir(out, sweep)
    count = workers or default_workers()
    with SweepStore(out, sweep) as store:
        rows = store.open()
        todo = list(pending(sweep, rows))
        progress = _progress(stderr, tty, len(sweep.points), rows)
        results = _results(todo, count, ray, pictures)
        ran = clean = errors = 0
        try:
            for point, outcome in results:
                row = store.record(point, outcome)
                ran += 1
                clean += bool(row["clean"])
                errors += row["status"] == "error"
                if progress is not None:
                    progress.finished(clean=bool(row["clean"]), error=row["status"] == "error")
                    if outcome.error is not None:
                        progress.note(
                            f"run {point.run_id}: {outcome.error.type}: {outcome.error.message}"
                        )
                if on_row is not None:
                    on_row(row)
        finally:
            results.close()
            if progress is not None:
                progress.close()
    summary = write_summary(out)
    return SweepReport(
        total=len(sweep.points),
        skipped=len(rows),
        ran=ran,
        clean=clean + sum(bool(r["clean"]) for r in rows),
        errors=errors + sum(r["status"] == "error" for r in rows),
        summary=summary,
    )


def _results(todo: list[Any], workers: int, ray: str | None, pictures: Pictures) -> Results:
    if ray is not None:
        return ray_tasks(todo, workers, None if ray == LOCAL_RAY else ray, pictures)
    if workers <= 1 or len(todo) <= 1:
        return serial(todo, pictures)
    return pool(todo, min(workers, len(todo)), pictures)


def _progress(
    stream: TextIO | None, tty: bool, total: int, rows: list[dict[str, Any]]
) -> SweepProgress | None:
    if stream is None:
        return None
    return SweepProgress(
        stream,
        total,
        skipped=len(rows),
        clean=sum(bool(r["clean"]) for r in rows),
        errors=sum(r["status"] == "error" for r in rows),
        tty=tty,
    )
