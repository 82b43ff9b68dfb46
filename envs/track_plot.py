"""Pictures of a track: cones by kind and the global path by covariance status.

The ROS pipeline's ``status_colored_path_publisher`` draws the global path in RViz as a
line strip, red where a point's covariance exceeds the threshold and green
otherwise; this is the same picture as a PNG, with the cones in their FS colours.
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import LineCollection
from matplotlib.figure import Figure

from conesim.tracks import ConeKind, Track
from conesim.tracks.global_path import GlobalPath

CONE_STYLE: dict[ConeKind, tuple[str, float]] = {
    ConeKind.BLUE: ("#1f4fd1", 14.0),
    ConeKind.YELLOW: ("#f2c200", 14.0),
    ConeKind.ORANGE: ("#ff7f0e", 14.0),
    ConeKind.BIG_ORANGE: ("#d94c00", 30.0),
    ConeKind.UNKNOWN: ("#808080", 14.0),
}
PATH_GREEN = "#2ca02c"
PATH_RED = "#d62728"


def draw_track(ax: Axes, track: Track, global_path: GlobalPath | None = None) -> None:
    """Draw cones by kind, the start pose, the start/finish line and the global path."""
    kinds = np.array([str(k) for k in track.kinds])
    for kind, (colour, size) in CONE_STYLE.items():
        mask = kinds == str(kind)
        if mask.any():
            ax.scatter(
                track.cones[mask, 0],
                track.cones[mask, 1],
                s=size,
                c=colour,
                edgecolors="black",
                linewidths=0.3,
                label=f"{kind} ({int(mask.sum())})",
                zorder=3,
            )
    if global_path is not None:
        draw_global_path(ax, global_path)
    sf = np.asarray(track.start_finish)
    ax.plot(sf[:, 0], sf[:, 1], color="black", lw=1.5, ls="--", label="start/finish", zorder=2)
    pose = track.start_pose
    ax.annotate(
        "",
        xy=(pose.x + 3.0 * np.cos(pose.yaw), pose.y + 3.0 * np.sin(pose.yaw)),
        xytext=(pose.x, pose.y),
        arrowprops={"arrowstyle": "->", "color": "black", "lw": 1.5},
        zorder=4,
    )
    ax.set_aspect("equal")
    ax.set_xlabel("x east in reference [m]")
    ax.set_ylabel("y north in reference [m]")
    ax.grid(True, lw=0.3, alpha=0.5)


def draw_global_path(ax: Axes, path: GlobalPath) -> None:
    """The global path as a line strip, each segment coloured by its start point's status."""
    ring = path.polyline.ring
    segments = np.stack([ring[:-1], ring[1:]], axis=1)
    red = path.high_covariance[: len(segments)]
    colours = [PATH_RED if r else PATH_GREEN for r in red]
    ax.add_collection(LineCollection(list(segments), colors=colours, linewidths=2.0, zorder=1))
    ax.plot([], [], color=PATH_GREEN, lw=2, label=f"global path, cov <= {path.cov_threshold:g} m²")
    ax.plot([], [], color=PATH_RED, lw=2, label=f"global path, cov > {path.cov_threshold:g} m²")


def save_track_picture(
    track: Track, global_path: GlobalPath | None, out: str | os.PathLike[str]
) -> Path:
    """Render the track picture to ``out`` (PNG), written atomically.

    Returns:
        The path written.
    """
    target = Path(out)
    fig = Figure(figsize=(9, 7), dpi=110)  # no pyplot state: headless and re-entrant
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    draw_track(ax, track, global_path)
    ax.set_title(f"{track.name}: {track.length_m:.0f} m, {len(track.cones)} cones")
    ax.legend(loc="upper left", fontsize=7, framealpha=0.8)
    save_figure(fig, target)
    return target


def save_figure(fig: Figure, out: Path) -> None:
    """Save ``fig`` as PNG at ``out`` atomically (temporary file + ``os.replace``).

    Missing parent directories are created, and removed again if the picture
    cannot be written, so a failure leaves nothing behind.

    Raises:
        OSError: ``out`` cannot be written (its ``filename`` may be the
            temporary file; name ``out`` in messages).
    """
    missing = []
    parent = out.parent
    while not parent.exists() and parent != parent.parent:
        missing.append(parent)
        parent = parent.parent
    tmp = out.with_name(f".{out.name}.tmp.png")
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(tmp, bbox_inches="tight", format="png")
        os.replace(tmp, out)
    except OSError:
        for directory in missing:  # innermost first
            with contextlib.suppress(OSError):
                directory.rmdir()
        raise
    finally:
        with contextlib.suppress(OSError):
            tmp.unlink(missing_ok=True)
