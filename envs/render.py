"""Drawing the ROS pipeline's RViz picture in 2D: the env's ``rgb_array`` and ``human`` modes.

What is drawn (``Scene``): the cones by kind (where they are now: knocked
cones move), the global path coloured by covariance status, the car's true
footprint, the EKF estimate with its 2-sigma covariance ellipse, the latest
detections placed with the estimated pose, the left/right classification, the
planned path, the waypoints with speed bars and the lookahead point.

``rgb_array`` renders with matplotlib's Agg canvas (no display needed);
``human`` shows the same frames in a pygame window (the ``render`` extra:
``pip install "conesim[render]"``).
"""

from __future__ import annotations

import contextlib
import math
import os
import sys
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import Ellipse, Polygon
from numpy.typing import NDArray

from conesim.core.messages import FRAME_OS_SENSOR, FRAME_REFERENCE, ConeDetections
from conesim.core.pose import Pose2D
from conesim.envs.loop import StepRecord
from conesim.envs.track_plot import CONE_STYLE, draw_global_path
from conesim.localization.ekf import Estimate
from conesim.localization.frames import LATEST, Buffer, TransformError
from conesim.planner.autopilot import Planned
from conesim.tracks import ConeKind
from conesim.tracks.global_path import GlobalPath

FloatArray = NDArray[np.float64]


def window_problem() -> str | None:
    """Why a ``human`` window cannot be shown here, or None: pygame missing (the
    ``render`` extra), or, on Linux, no display. Without one pygame falls back to a
    driver that shows nothing, so a run would draw every frame, slowly and unseen;
    a driver the user chose (``SDL_VIDEODRIVER``: kmsdrm, fbcon, dummy) is trusted."""
    try:
        import pygame  # noqa: F401, PLC0415
    except ImportError:
        return 'pygame is not installed; install the render extra: pip install "conesim[render]"'
    if (
        sys.platform.startswith("linux")
        and not os.environ.get("DISPLAY")
        and not os.environ.get("WAYLAND_DISPLAY")
        and not os.environ.get("SDL_VIDEODRIVER")
    ):
        return "no display (DISPLAY or WAYLAND_DISPLAY is not set)"
    return None


def _empty() -> FloatArray:
    return np.zeros((0, 2))


@dataclass
class Scene:
    """Everything one frame shows; arrays are in ``reference`` [m]."""

    cones: FloatArray
    kinds: tuple[str, ...]
    car: Pose2D
    car_length: float
    car_width: float
    t: float = 0.0
    speed: float = 0.0
    laps: int = 0
    estimate: Pose2D | None = None
    covariance: FloatArray | None = None  # (2, 2) position covariance [m^2]
    detections: FloatArray = field(default_factory=_empty)
    left: FloatArray = field(default_factory=_empty)
    right: FloatArray = field(default_factory=_empty)
    path: FloatArray = field(default_factory=_empty)
    speeds: FloatArray = field(default_factory=lambda: np.zeros(0))
    lookahead: FloatArray | None = None


class SceneKeeper:
    """Builds each frame's :class:`Scene` from the loop's records.

    Keeps, between records, the newest cone detection and the driver's newest
    plan (detections come at 10 Hz, plans with them; frames at the control
    rate).

    Args:
        kinds: the track's cone kinds, in cone order.
        car_length: the car's footprint length [m].
        car_width: its width [m].
    """

    def __init__(self, kinds: tuple[str, ...], car_length: float, car_width: float) -> None:
        self.kinds = kinds
        self.car_length = car_length
        self.car_width = car_width
        self.detections: ConeDetections | None = None
        self.planned: Planned | None = None
        self.record: StepRecord | None = None

    def update(self, record: StepRecord) -> None:
        """Take a record (every one, in order)."""
        for delivery in record.deliveries:
            if isinstance(delivery.message, ConeDetections):
                self.detections = delivery.message
        if record.driver is not None and record.driver.plans:
            self.planned = record.driver.plans[-1]
        self.record = record

    def scene(self, frames: Buffer, estimate: Estimate | None) -> Scene:
        """The scene of the last record: truth, ``estimate``, detections placed by ``frames``."""
        record = self.record
        assert record is not None, "SceneKeeper.scene() before update()"
        truth = record.truth
        scene = Scene(
            cones=truth.cones,
            kinds=self.kinds,
            car=truth.state.pose,
            car_length=self.car_length,
            car_width=self.car_width,
            t=record.t,
            speed=truth.state.speed,
            laps=truth.race.laps_completed,
        )
        if estimate is not None:
            scene.estimate = estimate.pose
            scene.covariance = np.asarray(estimate.pose_covariance)[:2, :2]
        det = self.detections
        if det is not None and len(det):
            with contextlib.suppress(TransformError):  # placed with the pose at capture
                scene.detections = frames.transform_points(
                    FRAME_REFERENCE,
                    FRAME_OS_SENSOR,
                    np.asarray(det.points[:, :2]),
                    det.header.stamp,
                )
        out = record.driver
        if self.planned is not None and out is not None:
            scene.left = np.asarray(self.planned.classified.left)
            scene.right = np.asarray(self.planned.classified.right)
            scene.path = np.asarray(out.path_reference)
            if len(self.planned.plan.speeds) == len(scene.path):
                scene.speeds = np.asarray(self.planned.plan.speeds)
            if out.lookahead is not None:
                with contextlib.suppress(TransformError):
                    scene.lookahead = frames.transform_points(
                        FRAME_REFERENCE, FRAME_OS_SENSOR, np.asarray(out.lookahead).reshape(1, 2),
                        LATEST,
                    )[0]  # fmt: skip
        return scene


class Renderer:
    """Renders scenes to RGB arrays, centred on the car.

    Args:
        global_path: drawn under everything.
        size: image width and height [px].
        view: side of the square view [m].
    """

    def __init__(self, global_path: GlobalPath, size: int = 480, view: float = 40.0) -> None:
        self.global_path = global_path
        self.size = size
        self.view = view
        self._window: Any = None
        self._clock: Any = None

    def rgb_array(self, scene: Scene) -> NDArray[np.uint8]:
        """The frame as a (size, size, 3) uint8 array."""
        dpi = 100
        # A bare Figure on an Agg canvas: no pyplot state, no display needed.
        fig = Figure(figsize=(self.size / dpi, self.size / dpi), dpi=dpi)
        canvas = FigureCanvasAgg(fig)
        ax = fig.add_axes((0.0, 0.0, 1.0, 1.0))
        self._draw(ax, scene)
        canvas.draw()
        return np.asarray(canvas.buffer_rgba())[:, :, :3].copy()

    def _draw(self, ax: Axes, sc: Scene) -> None:
        half = 0.5 * self.view
        ax.set_xlim(sc.car.x - half, sc.car.x + half)
        ax.set_ylim(sc.car.y - half, sc.car.y + half)
        ax.set_aspect("equal")
        ax.set_facecolor("#e8e8e8")
        ax.set_xticks([])
        ax.set_yticks([])
        draw_global_path(ax, self.global_path)
        kinds = np.array(sc.kinds)
        for kind, (colour, size) in CONE_STYLE.items():
            mask = kinds == str(kind)
            if mask.any():
                ax.scatter(
                    sc.cones[mask][:, 0],
                    sc.cones[mask][:, 1],
                    s=size * 2,
                    c=colour,
                    edgecolors="k",
                    linewidths=0.4,
                )
        if len(sc.left):
            ax.scatter(
                sc.left[:, 0],
                sc.left[:, 1],
                s=90,
                facecolors="none",
                edgecolors=CONE_STYLE[ConeKind.BLUE][0],
            )
        if len(sc.right):
            ax.scatter(
                sc.right[:, 0],
                sc.right[:, 1],
                s=90,
                facecolors="none",
                edgecolors=CONE_STYLE[ConeKind.YELLOW][0],
            )
        if len(sc.detections):
            ax.scatter(
                sc.detections[:, 0],
                sc.detections[:, 1],
                s=12,
                marker="x",
                c="#444444",
                linewidths=0.8,
            )
        if len(sc.path) > 1:
            ax.plot(*sc.path.T, color="#c000c0", lw=1.5)
            ax.scatter(sc.path[:, 0], sc.path[:, 1], s=4, c="#c000c0")
            self._speed_bars(ax, sc)
        if sc.lookahead is not None:
            ax.scatter(sc.lookahead[0], sc.lookahead[1], s=40, marker="*", c="#c000c0")
        self._car(ax, sc)
        ax.text(
            0.02, 0.98,
            f"t {sc.t:6.2f} s   v {sc.speed:5.2f} m/s   laps {sc.laps}",
            transform=ax.transAxes, va="top", fontsize=8, family="monospace",
        )  # fmt: skip

    def _speed_bars(self, ax: Axes, sc: Scene) -> None:
        # Waypoint speed bars (the ROS pipeline's /waypoint_speed_bars, seen from above):
        # a bar normal to the path whose length is the speed at 0.1 m per m/s.
        if len(sc.speeds) != len(sc.path):
            return
        d = np.gradient(sc.path, axis=0)
        n = np.column_stack([-d[:, 1], d[:, 0]])
        n /= np.maximum(np.hypot(*n.T), 1e-9)[:, None]
        tips = sc.path + n * (0.1 * sc.speeds)[:, None]
        for a, b in zip(sc.path[::2], tips[::2], strict=True):
            ax.plot([a[0], b[0]], [a[1], b[1]], color="#2ca02c", lw=1.0, alpha=0.6)

    def _car(self, ax: Axes, sc: Scene) -> None:
        hl, hw = 0.5 * sc.car_length, 0.5 * sc.car_width
        corners = sc.car.transform_points([[hl, hw], [-hl, hw], [-hl, -hw], [hl, -hw]])
        ax.add_patch(Polygon(corners, closed=True, fc="#d62728", ec="k", alpha=0.8))
        if sc.estimate is not None:
            est = sc.estimate
            ax.plot(
                [est.x, est.x + 1.5 * math.cos(est.yaw)],
                [est.y, est.y + 1.5 * math.sin(est.yaw)],
                color="#1f77b4", lw=2,
            )  # fmt: skip
            if sc.covariance is not None and np.all(np.isfinite(sc.covariance)):
                vals, vecs = np.linalg.eigh(sc.covariance)
                vals = np.maximum(vals, 0.0)
                angle = math.degrees(math.atan2(vecs[1, 1], vecs[0, 1]))
                width, height = 2 * 2 * math.sqrt(vals[1]), 2 * 2 * math.sqrt(vals[0])
                ax.add_patch(
                    Ellipse((est.x, est.y), max(width, 0.05), max(height, 0.05), angle=angle,
                            fc="none", ec="#1f77b4", lw=1.2)
                )  # fmt: skip

    def show(self, frame: NDArray[np.uint8], fps: float) -> None:
        """Show a frame in a pygame window (``human`` mode; ``window_problem`` was asked
        when the mode was chosen)."""
        import pygame  # noqa: PLC0415

        if self._window is None:
            # Only the display: pygame.init() also opens the audio device,
            # which prints ALSA errors on a machine without one.
            pygame.display.init()
            self._window = pygame.display.set_mode((frame.shape[1], frame.shape[0]))
            pygame.display.set_caption("conesim")
            self._clock = pygame.time.Clock()
        surface = pygame.surfarray.make_surface(np.transpose(frame, (1, 0, 2)))
        self._window.blit(surface, (0, 0))
        pygame.event.pump()
        pygame.display.flip()
        self._clock.tick(fps)

    def close(self) -> None:
        """Close the window, if any."""
        if self._window is not None:
            import pygame  # noqa: PLC0415

            pygame.display.quit()
            pygame.quit()
            self._window = None
