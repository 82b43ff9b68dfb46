"""A sweep's summary: a table per axis, a picture of them, and the runs that failed.

From a sweep directory's rows (``envs.sweep_store``), for each axis, one
line per value of it (``axis_tables``):

* runs, clean (every lap completed, no cone down or out, no off-track
  event; ``RunResult.clean``) and the clean rate, errors (runs that raised);
* laps completed of the laps to drive, cones down or out, off-track events
  (totals over the runs that finished without an error);
* the lap-time ratio (best lap over the friction-limited lap) and the
  localization RMSE, each the median over the runs that have one.

``write_summary`` writes ``summary.md`` (the tables), ``summary.png``
(clean rate per condition, and the distribution of lap-time ratios per
condition) and ``failed.md`` (every run that was not clean, with its reason
and its ``run.png``), and returns the tables' text, which ``conesim sweep``
prints. ``conesim sweep summary DIR`` writes them again from the rows.
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from conesim.envs.run_dir import write_together
from conesim.envs.sweep_store import MANIFEST, RESULTS, RUNS, read_manifest, read_rows
from conesim.envs.track_plot import save_figure

Row = Mapping[str, Any]


@dataclass(frozen=True)
class ValueStats:
    """One line of an axis's table (see the module docstring)."""

    value: str
    runs: int
    clean: int
    errors: int
    laps_completed: int
    laps: int
    cones_down_or_out: int
    off_track_events: int
    lap_time_ratio: float | None  # median [-]
    localization_rmse_m: float | None  # median [m]
    ratios: tuple[float, ...]  # every run's lap-time ratio [-]

    @property
    def clean_rate(self) -> float:
        """Clean runs per run [-]."""
        return self.clean / self.runs if self.runs else math.nan


def _median(values: Iterable[Any]) -> float | None:
    finite = [float(v) for v in values if v is not None and math.isfinite(v)]
    return statistics.median(finite) if finite else None


def value_stats(value: str, rows: Sequence[Row]) -> ValueStats:
    """The line of the rows that have this value."""
    ok = [r for r in rows if r.get("status") == "ok"]
    ratios = tuple(
        float(r["lap_time_ratio"])
        for r in ok
        if r.get("lap_time_ratio") is not None and math.isfinite(r["lap_time_ratio"])
    )
    return ValueStats(
        value=value,
        runs=len(rows),
        clean=sum(bool(r.get("clean")) for r in rows),
        errors=len(rows) - len(ok),
        laps_completed=sum(int(r["laps_completed"]) for r in ok),
        laps=sum(int(r["laps"]) for r in ok),
        cones_down_or_out=sum(int(r["cones_down_or_out"]) for r in ok),
        off_track_events=sum(int(r["off_track_events"]) for r in ok),
        lap_time_ratio=_median(ratios),
        localization_rmse_m=_median(r.get("localization_pos_rmse_m") for r in ok),
        ratios=ratios,
    )


def axis_tables(rows: Sequence[Row], axes: Sequence[str]) -> dict[str, list[ValueStats]]:
    """Per axis, a line per value, in the order the values first appear by run index."""
    ordered = sorted(rows, key=lambda r: r.get("index", 0))
    tables = {}
    for axis in axes:
        groups: dict[str, list[Row]] = {}
        for row in ordered:
            groups.setdefault(str(row["axes"].get(axis)), []).append(row)
        tables[axis] = [value_stats(value, group) for value, group in groups.items()]
    return tables


def _num(value: float | None, fmt: str) -> str:
    return "n/a" if value is None else format(value, fmt)


HEADER = (
    "| value | runs | clean | clean rate | errors | laps completed | cones down/out "
    "| off-track events | lap-time ratio (median) | loc. RMSE [m] (median) |"
)


def table_markdown(axis: str, lines: Sequence[ValueStats]) -> str:
    """One axis's table in Markdown."""
    out = [f"### {axis}", "", HEADER, "|" + "---|" * 10]
    for s in lines:
        out.append(
            f"| {s.value} | {s.runs} | {s.clean} | {s.clean_rate:.0%} | {s.errors} "
            f"| {s.laps_completed}/{s.laps} | {s.cones_down_or_out} | {s.off_track_events} "
            f"| {_num(s.lap_time_ratio, '.3f')} | {_num(s.localization_rmse_m, '.3f')} |"
        )
    return "\n".join(out)


def summary_markdown(rows: Sequence[Row], axes: Sequence[str], total: int) -> str:
    """``summary.md``: the overall line, then a table per axis."""
    overall = value_stats("all", rows)
    head = [
        "# Sweep summary",
        "",
        f"{overall.runs} of {total} runs done: {overall.clean} clean "
        f"({overall.clean_rate:.0%}), {overall.errors} errors; median lap-time ratio "
        f"{_num(overall.lap_time_ratio, '.3f')}, median localization RMSE "
        f"{_num(overall.localization_rmse_m, '.3f')} m.",
        "",
        "Clean: every lap completed, no cone down or out, no off-track event. Totals of laps, "
        "cones and off-track events are over the runs without an error.",
    ]
    tables = axis_tables(rows, axes)
    return "\n\n".join(["\n".join(head), *(table_markdown(a, t) for a, t in tables.items())]) + "\n"


def failure_reason(row: Row) -> str:
    """Why a run is not clean: its error, or what happened."""
    if row.get("status") == "error":
        error = row.get("error", {})
        return f"error: {error.get('type')}: {error.get('message')}"
    parts = []
    if not row.get("finished"):
        parts.append(
            f"{row.get('laps_completed')}/{row.get('laps')} laps ({row.get('end_reason')})"
        )
    if row.get("cones_down_or_out"):
        parts.append(f"{row['cones_down_or_out']} cones down or out")
    if row.get("off_track_events"):
        parts.append(f"{row['off_track_events']} off-track events")
    return ", ".join(parts) or "not clean"


def failed_markdown(rows: Sequence[Row], out: Path) -> str:
    """``failed.md`` of the sweep in ``out``: each run that was not clean, its labels,
    reason and picture (or its result.json when it has none, or its traceback)."""
    failed = sorted((r for r in rows if not r.get("clean")), key=lambda r: r.get("index", 0))
    lines = ["# Runs that failed", "", f"{len(failed)} of {len(rows)} runs were not clean."]
    for row in failed:
        run = f"{RUNS}/{row['run_id']}"
        labels = ", ".join(f"{k} = {v}" for k, v in row["axes"].items())
        lines += ["", f"## {row['run_id']}", "", f"{labels}: **{failure_reason(row)}**", ""]
        if row.get("status") == "error":
            lines.append(f"Traceback: [{run}/error.txt]({run}/error.txt)")
        elif (out / run / "run.png").is_file():
            lines.append(f"[![{row['run_id']}]({run}/run.png)]({run}/result.json)")
        else:
            lines.append(f"[{run}/result.json]({run}/result.json)")
    return "\n".join(lines) + "\n"


def save_summary_picture(tables: Mapping[str, Sequence[ValueStats]], out: Path) -> Path:
    """Clean rate per condition (bars) beside its lap-time ratios (box plots): PNG."""
    lines = [(f"{axis} = {s.value}", s) for axis, stats in tables.items() for s in stats]
    height = max(3.0, 0.35 * len(lines) + 1.5)
    fig = Figure(figsize=(12, height), dpi=100)
    FigureCanvasAgg(fig)
    ax_clean, ax_ratio = fig.subplots(1, 2, sharey=True)
    y = list(range(len(lines)))[::-1]
    rates = [0.0 if s.runs == 0 else s.clean_rate for _, s in lines]
    ax_clean.barh(y, rates, color="#98df8a", height=0.6)
    for yi, (_, s) in zip(y, lines, strict=True):
        ax_clean.text(0.01, yi, f"{s.clean}/{s.runs}", va="center", fontsize=7, color="black")
    ax_clean.set_yticks(y, [label for label, _ in lines], fontsize=8)
    ax_clean.set_xlim(0.0, 1.0)
    ax_clean.set_xlabel("clean rate [-]")
    ax_clean.set_title("clean runs per condition")
    ax_clean.grid(True, axis="x", lw=0.3)
    with_ratios = [(yi, s.ratios) for yi, (_, s) in zip(y, lines, strict=True) if s.ratios]
    if with_ratios:
        ax_ratio.boxplot(
            [list(r) for _, r in with_ratios], positions=[yi for yi, _ in with_ratios],
            orientation="horizontal", widths=0.6, manage_ticks=False,
        )  # fmt: skip
    ax_ratio.ticklabel_format(axis="x", useOffset=False)
    ax_ratio.set_xlabel("lap-time ratio: best lap / friction-limited lap [-]")
    ax_ratio.set_title("lap-time ratios per condition (runs without an error)")
    ax_ratio.grid(True, axis="x", lw=0.3)
    fig.tight_layout()
    save_figure(fig, out)
    return out


def write_summary(out: Path) -> str:
    """Write ``summary.md``, ``summary.png`` and ``failed.md`` into a sweep's directory.

    Returns:
        ``summary.md``'s text.

    Raises:
        FileNotFoundError: ``out`` holds no sweep (no ``sweep.json``).
    """
    made = read_manifest(out)
    if made is None:
        raise FileNotFoundError(f"{out}: no {MANIFEST}: not a sweep's directory")
    axes = [str(a) for a in made.get("axes", [])]
    rows = read_rows(out / RESULTS)
    text = summary_markdown(rows, axes, len(made.get("runs", [])))
    failed = failed_markdown(rows, out)
    save_summary_picture(axis_tables(rows, axes), out / "summary.png")
    write_together(
        out,
        {
            "summary.md": lambda p: p.write_text(text, encoding="utf-8"),
            "failed.md": lambda p: p.write_text(failed, encoding="utf-8"),
        },
    )
    return text
