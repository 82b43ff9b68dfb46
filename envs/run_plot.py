"""``run.png``: a run at a glance.

Three panels: the car's trajectory on the track (cones by kind, the global
path by covariance status), the localization error over time (position and
heading, sampled at every TF broadcast), and the speed against the planned
speed.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from conesim.envs.track_plot import draw_track, save_figure
from conesim.tracks import Track
from conesim.tracks.global_path import GlobalPath

if TYPE_CHECKING:  # the closed loop (and its compiled kernels) loads only for a run
    from conesim.envs.runner import RunResult


def save_run_picture(result: RunResult, track: Track, path: GlobalPath, out: Path) -> Path:
    """Draw the three panels to ``out`` (PNG, written atomically)."""
    tr = result.trace
    fig = Figure(figsize=(14, 5), dpi=100)
    FigureCanvasAgg(fig)
    ax_map, ax_loc, ax_speed = fig.subplots(1, 3, gridspec_kw={"width_ratios": [1.3, 1, 1]})
    draw_track(ax_map, track, path)
    ax_map.plot(tr.x, tr.y, color="#9400d3", lw=1.2, label="car (CG, truth)")
    ax_map.legend(loc="upper left", fontsize=6, framealpha=0.8)
    ax_map.set_title(
        f"{result.track}: {result.laps_completed}/{result.laps} laps, {result.end_reason}"
    )

    ax_loc.plot(tr.loc_t, tr.loc_pos_err, color="#1f77b4", lw=1.0, label="position [m]")
    ax_loc.set_xlabel("time [s]")
    ax_loc.set_ylabel("position error [m]")
    twin = ax_loc.twinx()
    twin.plot(tr.loc_t, np.degrees(tr.loc_yaw_err), color="#ff7f0e", lw=0.8, label="heading [deg]")
    twin.set_ylabel("heading error [deg]")
    pos = result.localization_pos_rmse_m
    yaw = result.localization_yaw_rmse_deg
    ax_loc.set_title(
        f"{result.localization} localization, {result.sensors} sensors: RMSE "
        + ("n/a" if pos is None or yaw is None else f"{pos:.3f} m, {yaw:.2f} deg")
    )
    ax_loc.grid(True, lw=0.3)

    ax_speed.plot(tr.t, tr.speed, color="#2ca02c", lw=1.0, label="speed (truth)")
    ax_speed.plot(tr.t, tr.target_speed, color="#c000c0", lw=0.8, ls="--", label="planned speed")
    ax_speed.set_xlabel("time [s]")
    ax_speed.set_ylabel("speed [m/s]")
    laps = ", ".join(f"{t:.2f}" for t in result.lap_times_s) or "none"
    ratio = result.lap_time_ratio
    ax_speed.set_title(
        f"laps [s]: {laps}; limit {result.limit_lap_time_s:.2f} s"
        + ("" if ratio is None or not math.isfinite(ratio) else f" ({ratio:.2f}x)")
    )
    ax_speed.legend(loc="lower right", fontsize=7)
    ax_speed.grid(True, lw=0.3)
    fig.tight_layout()
    save_figure(fig, out)
    return out
