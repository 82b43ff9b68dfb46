"""Tests for the observation's path preview: worked points on a line and a
circle, wrapping and clamping at the path's ends, and the env's entries."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from numpy.testing import assert_allclose

from conesim.core.polyline import Polyline
from conesim.core.pose import Pose2D
from conesim.envs.cone_track_env import ConeTrackEnv
from conesim.envs.config import EnvConfig
from conesim.envs.observation import PathPreview


def _circle(radius: float, points: int) -> Polyline:
    """A closed counter-clockwise circle about the origin, starting at (radius, 0)."""
    a = np.linspace(0.0, 2.0 * math.pi, points, endpoint=False)
    return Polyline(radius * np.column_stack([np.cos(a), np.sin(a)]), True)


def test_preview_on_a_line_is_the_path_ahead_in_the_car_frame() -> None:
    """A car 1 m left of a path along +x at x = 10, heading along it: the
    points 2, 4, 6 m ahead are at (2, -1), (4, -1), (6, -1); turned 90 deg
    left, the same points are (-1, -2) ... (x forward, y left)."""
    line = Polyline(np.array([[0.0, 0.0], [50.0, 0.0], [100.0, 0.0]]), False)
    preview = PathPreview(line, 3, 2.0)
    assert preview.length == 6.0
    assert_allclose(preview.points(Pose2D(10.0, 1.0, 0.0)), [[2, -1], [4, -1], [6, -1]])
    turned = PathPreview(line, 3, 2.0).points(Pose2D(10.0, 1.0, math.pi / 2))
    assert_allclose(turned, [[-1, -2], [-1, -4], [-1, -6]], atol=1e-12)


def test_preview_on_a_circle_bends_left_by_the_arc() -> None:
    """On a circle of 20 m, counter-clockwise, the car on it heading along it:
    the point s ahead is at (R sin(s/R), R (1 - cos(s/R))), so 15 m ahead is
    (13.63, 5.37) m (to the chords' 1e-3 m)."""
    r = 20.0
    preview = PathPreview(_circle(r, 720), 5, 3.0)
    s = 3.0 * np.arange(1, 6)
    expected = np.column_stack([r * np.sin(s / r), r * (1.0 - np.cos(s / r))])
    assert_allclose(preview.points(Pose2D(r, 0.0, math.pi / 2)), expected, atol=1e-3)
    assert expected[-1] == pytest.approx([13.633, 5.366], abs=1e-3)


def test_preview_wraps_a_loop_and_clamps_an_open_path() -> None:
    """Just before a loop's end the points run on past its start; on an open
    path the points beyond its end stay at the end."""
    r = 20.0
    loop = _circle(r, 720)
    before_end = 2.0 * math.pi * r - 1.0  # 1 m of arc before the start point
    angle = before_end / r
    pose = Pose2D(r * math.cos(angle), r * math.sin(angle), angle + math.pi / 2)
    pts = PathPreview(loop, 2, 2.0).points(pose)
    s = np.array([2.0, 4.0])
    assert_allclose(pts, np.column_stack([r * np.sin(s / r), r * (1 - np.cos(s / r))]), atol=1e-3)
    line = Polyline(np.array([[0.0, 0.0], [10.0, 0.0]]), False)
    assert_allclose(
        PathPreview(line, 3, 2.0).points(Pose2D(7.0, 0.0, 0.0)), [[2, 0], [3, 0], [3, 0]]
    )


def test_preview_rejoins_the_path_where_the_car_is() -> None:
    """A hairpin, two legs 6 m apart: walked along the first leg, then put on the
    second heading back (a cut across the infield), the preview shows the second
    leg ahead, (2, 0) and (4, 0), not the first leg 6 m to its side."""
    leg = np.arange(0.0, 51.0)
    turn = np.linspace(-math.pi / 2, math.pi / 2, 20)[1:-1]
    points = np.vstack(
        [
            np.column_stack([leg, np.zeros_like(leg)]),
            np.column_stack([50.0 + 3.0 * np.cos(turn), 3.0 + 3.0 * np.sin(turn)]),
            np.column_stack([leg[::-1], np.full_like(leg, 6.0)]),
        ]
    )
    preview = PathPreview(Polyline(points, False), 2, 2.0)
    for x in (10.0, 20.0, 30.0):
        assert_allclose(preview.points(Pose2D(x, 0.2, 0.0)), [[2, -0.2], [4, -0.2]], atol=1e-9)
    assert_allclose(preview.points(Pose2D(30.0, 6.0, math.pi)), [[2, 0], [4, 0]], atol=1e-9)


def _truth_points(env: ConeTrackEnv) -> np.ndarray:
    """The preview worked out apart: the exact projection of the antenna's pose."""
    pose = env.loop.localizer.published_pose()
    assert pose is not None
    line = env.loop.global_path.polyline
    station = float(line.project(np.array([pose.x, pose.y])).station[0])
    ahead = line.at(
        station + env.config.path_preview_step * np.arange(1, 1 + env.config.path_preview)
    )
    d = ahead - [pose.x, pose.y]
    c, s = math.cos(pose.yaw), math.sin(pose.yaw)
    return np.column_stack([c * d[:, 0] + s * d[:, 1], c * d[:, 1] - s * d[:, 0]])


def test_env_appends_the_preview_scaled_by_its_length() -> None:
    """Vector mode: 8 + 5 K + 2 N entries, the last 2 N the preview over N x step
    (10 x 3 m), as worked out from the frame tree's pose; the dict mode's
    ``path`` in metres; without a preview the observation is as before."""
    kwargs: dict[str, Any] = {"track": "autocross", "sensors": "ideal", "localization": "truth"}
    env = ConeTrackEnv(path_preview=10, path_preview_step=3.0, **kwargs)
    assert env.observation_space.shape == (8 + 5 * 32 + 20,)
    env.reset(seed=0)
    for _ in range(100):
        obs, *_ = env.step(np.array([0.1, 0.6], dtype=np.float32))
    assert env.observation_space.contains(obs)
    assert_allclose(obs[-20:].reshape(10, 2), _truth_points(env) / 30.0, atol=1e-5)
    assert obs[-2] > 0.5  # the last point well ahead of the car
    dict_env = ConeTrackEnv(path_preview=10, path_preview_step=3.0, observation="dict", **kwargs)
    dict_env.reset(seed=0)
    for _ in range(100):
        d_obs, *_ = dict_env.step(np.array([0.1, 0.6], dtype=np.float32))
    assert_allclose(d_obs["path"], _truth_points(dict_env), atol=1e-4)
    env.reset(seed=0, options={"track": "skidpad"})  # another track: its own path
    for _ in range(100):
        obs, *_ = env.step(np.array([0.0, 0.6], dtype=np.float32))
    assert_allclose(obs[-20:].reshape(10, 2), _truth_points(env) / 30.0, atol=1e-5)
    assert ConeTrackEnv(**kwargs).observation_space.shape == (8 + 5 * 32,)
    assert "path" not in ConeTrackEnv(observation="dict", **kwargs).observation_space.spaces


def test_preview_is_zero_until_the_filter_has_a_pose() -> None:
    """Fused localization at reset, before the EKF's first estimate: pose_valid
    0 and the preview's entries 0; once it has one, the preview is the path."""
    env = ConeTrackEnv(track="autocross", path_preview=4)
    obs, _ = env.reset(seed=0)
    assert obs[4] == 0.0 and not obs[-8:].any()
    for _ in range(50):
        obs, *_ = env.step(np.zeros(2, dtype=np.float32))
    assert obs[4] == 1.0 and obs[-2] > 0.5


@pytest.mark.parametrize("observation", ["vector", "dict"])
def test_check_env_with_a_preview(observation: str) -> None:
    """gymnasium's checker passes with a path preview in both modes."""
    env = ConeTrackEnv(time_limit=2.0, path_preview=8, observation=observation)
    check_env(env, skip_render_check=True)


def test_config_refuses_a_bad_preview_by_name() -> None:
    """A negative, fractional or bool count, a spacing under 0.1 m or NaN, or a preview
    longer than 100 m raises naming the key."""
    for key, value in (
        ("path_preview", -1),
        ("path_preview", 2.5),
        ("path_preview", True),
        ("path_preview_step", 0.05),
        ("path_preview_step", float("nan")),
    ):
        with pytest.raises(ValueError, match=f"EnvConfig.{key}"):
            EnvConfig.from_dict({key: value})
    with pytest.raises(ValueError, match="path_preview x path_preview_step must be <= 100 m"):
        EnvConfig(path_preview=40, path_preview_step=3.0)
