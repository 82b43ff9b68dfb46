"""``run.png``: a run at a glance, with what happened marked.

Three panels:

- the map: the cones by kind, the global path by covariance status, the
  racing line of the lap-time limit (a loop's; ``planner.racing_line``), the
  car's trajectory (its CG, the truth) drawn over them, and the run's events:
  cones hit (rings) and knocked down or out (crosses), the stretches driven
  off the track (red), where each lap ended (numbered) and where the run
  ended, with why;
- the localization error over time (position and heading, at every TF
  broadcast), off-track stretches shaded;
- the speed against the planned speed, the laps' ends as vertical lines.

Every line has a legend entry; the map's legend sits beside the map, not on
the track.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from conesim.envs.track_plot import draw_track, save_figure
from conesim.tracks import Track
from conesim.tracks.global_path import GlobalPath

if TYPE_CHECKING:  # the closed loop (and its compiled kernels) loads only for a run
    from conesim.envs.metrics import ConeEventRecord
    from conesim.envs.runner import RunResult

TRAJECTORY = "#9400d3"
EVENT = "#d62728"
RACING_LINE = "#ff8c00"


def save_run_picture(result: RunResult, track: Track, path: GlobalPath, out: Path) -> Path:
    """Draw the three panels to ``out`` (PNG, written atomically)."""
    fig = Figure(figsize=(16, 5.5), dpi=100)
    FigureCanvasAgg(fig)
    ax_map, ax_loc, ax_speed = fig.subplots(1, 3, gridspec_kw={"width_ratios": [1.3, 1, 1]})
    _map(ax_map, result, track, path)
    _localization(ax_loc, result)
    _speed(ax_speed, result)
    fig.tight_layout()
    save_figure(fig, out)
    return out


def _map(ax: Axes, result: RunResult, track: Track, path: GlobalPath) -> None:
    tr = result.trace
    ev = result.events
    draw_track(ax, track, path)
    if result.racing_line is not None:
        line = np.vstack([result.racing_line, result.racing_line[:1]])  # a loop, closed
        ax.plot(
            line[:, 0], line[:, 1], color=RACING_LINE, lw=0.9, ls="--",
            label=f"racing line (limit {result.limit_lap_time_s:.2f} s)", zorder=4,
        )  # fmt: skip
    x, y, t = np.asarray(tr.x), np.asarray(tr.y), np.asarray(tr.t)
    ax.plot(x, y, color=TRAJECTORY, lw=1.4, label="car (CG, truth)", zorder=5)
    for k, excursion in enumerate(ev.off_track):
        end = excursion.t_end if excursion.t_end is not None else math.inf
        off = (t >= excursion.t_start) & (t <= end)
        label = f"off track ({len(ev.off_track)})" if k == 0 else None
        ax.plot(x[off], y[off], color=EVENT, lw=3.0, label=label, zorder=6)
    cone_marks: tuple[tuple[str, list[ConeEventRecord], dict[str, Any]], ...] = (
        ("cone hit", ev.cones_hit, {"s": 90, "facecolors": "none", "edgecolors": EVENT,
                                    "linewidths": 1.2, "zorder": 7}),
        ("cone down or out", ev.cones_down_or_out, {"s": 60, "marker": "x", "c": EVENT,
                                                    "linewidths": 1.6, "zorder": 8}),
    )  # fmt: skip
    for name, cones, style in cone_marks:
        if cones:
            xy = np.array([(c.x, c.y) for c in cones])
            ax.scatter(xy[:, 0], xy[:, 1], label=f"{name} ({len(cones)})", **style)
    ends = [int(np.argmin(np.abs(t - lap.t))) for lap in ev.laps] if len(t) else []
    if ends:
        ax.scatter(
            x[ends], y[ends], s=40, c="black", marker="D",
            label=f"lap ends ({len(ends)}): " + ", ".join(f"{lap.time_s:.2f} s" for lap in ev.laps),
            zorder=9,
        )  # fmt: skip
        for k, (i, lap) in enumerate(zip(ends, ev.laps, strict=True)):
            ax.annotate(
                str(lap.lap), (x[i], y[i]), xytext=(6, 6 + 9 * k), textcoords="offset points",
                fontsize=7, zorder=9,
            )  # fmt: skip
    if ev.end is not None:
        ax.scatter(
            [ev.end.x], [ev.end.y], s=140, marker="*", c="black", edgecolors="white",
            label=f"end: {ev.end.reason} at {ev.end.t:.1f} s", zorder=10,
        )  # fmt: skip
    ax.set_title(f"{result.track}: {result.laps_completed}/{result.laps} laps, {result.end_reason}")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=6, framealpha=0.9)


def _shade_off_track(ax: Axes, result: RunResult) -> None:
    for excursion in result.events.off_track:
        end = excursion.t_end if excursion.t_end is not None else result.sim_time_s
        ax.axvspan(excursion.t_start, end, color=EVENT, alpha=0.15, lw=0)


def _localization(ax: Axes, result: RunResult) -> None:
    tr = result.trace
    (pos,) = ax.plot(tr.loc_t, tr.loc_pos_err, color="#1f77b4", lw=1.0, label="position [m]")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("position error [m]")
    twin = ax.twinx()
    (yaw,) = twin.plot(
        tr.loc_t, np.degrees(tr.loc_yaw_err), color="#ff7f0e", lw=0.8, label="heading [deg]"
    )
    twin.set_ylabel("heading error [deg]")
    _shade_off_track(ax, result)
    rmse_pos = result.localization_pos_rmse_m
    rmse_yaw = result.localization_yaw_rmse_deg
    ax.set_title(
        f"{result.localization} localization, {result.sensors} sensors: RMSE "
        + (
            "n/a"
            if rmse_pos is None or rmse_yaw is None
            else f"{rmse_pos:.3f} m, {rmse_yaw:.2f} deg"
        )
    )
    ax.legend(handles=[pos, yaw], loc="upper right", fontsize=7)
    ax.grid(True, lw=0.3)


def _speed(ax: Axes, result: RunResult) -> None:
    tr = result.trace
    ax.plot(tr.t, tr.speed, color="#2ca02c", lw=1.0, label="speed (truth)")
    ax.plot(tr.t, tr.target_speed, color="#c000c0", lw=0.8, ls="--", label="planned speed")
    for k, lap in enumerate(result.events.laps):
        ax.axvline(lap.t, color="black", lw=0.6, ls=":", label="lap ends" if k == 0 else None)
    _shade_off_track(ax, result)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("speed [m/s]")
    laps = ", ".join(f"{t:.2f}" for t in result.lap_times_s) or "none"
    ratio = result.lap_time_ratio
    ax.set_title(
        f"laps [s]: {laps}; limit {result.limit_lap_time_s:.2f} s"
        + ("" if ratio is None or not math.isfinite(ratio) else f" ({ratio:.2f}x)")
    )
    ax.legend(loc="lower right", fontsize=7)
    ax.grid(True, lw=0.3)
