"""Tests for the ConeTrack-v0 env: gymnasium's checks, determinism, vector envs."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from numpy.testing import assert_allclose

from conesim import envs
from conesim.envs.cone_track_env import END_REASONS, ConeTrackEnv
from conesim.envs.config import EnvConfig
from conesim.envs.expert import AutopilotExpert
from conesim.planner import AutopilotConfig


def test_registered_and_made_with_one_import() -> None:
    """gym.make finds conesim/ConeTrack-v0 after `import conesim`, with max_episode_steps."""
    env = gym.make(envs.ENV_ID)
    assert env.spec is not None
    assert env.spec.max_episode_steps == envs.DEFAULT_MAX_EPISODE_STEPS
    env.close()


@pytest.mark.parametrize("observation", ["vector", "dict"])
def test_gymnasium_check_env_with_render(observation: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """gymnasium's env checker passes, render checks of both modes included."""
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")  # `human` mode without a display
    monkeypatch.setenv("SDL_AUDIODRIVER", "dummy")
    env = gym.make(envs.ENV_ID, render_mode="rgb_array", observation=observation, time_limit=2.0)
    check_env(env.unwrapped, skip_render_check=False)
    env.reset(seed=0)
    frame = env.render()
    assert frame is not None and frame.shape == (480, 480, 3) and frame.dtype == np.uint8
    env.close()


def rollout(seed: int, steps: int = 150) -> list[tuple[bytes, float, str]]:
    """Observations, rewards and info summaries of a fixed-action rollout."""
    env = ConeTrackEnv(info="full")
    obs, info = env.reset(seed=seed)
    out = [(obs.tobytes(), 0.0, repr(info["truth"]))]
    for k in range(steps):
        action = np.array([0.3 * math.sin(k / 20), 0.5], dtype=np.float32)
        obs, reward, _, _, info = env.step(action)
        terms = repr(sorted(info["reward_terms"].items()))
        out.append((obs.tobytes(), float(reward), repr(info["truth"]) + terms))
    return out


def test_same_seed_same_rollout_bit_for_bit() -> None:
    """The same seed gives identical observations, rewards and infos; another seed differs."""
    a, b, c = rollout(5), rollout(5), rollout(6)
    assert a == b
    assert a != c


def test_action_mapping_to_vehicle_limits() -> None:
    """Centred: [1, 1] is full left lock and +3 m/s^2, [-1, -1] full right and
    -3 m/s^2, beyond the box clipped; physical: radians and m/s^2, down to -10."""
    env = ConeTrackEnv()
    assert_allclose(env.action_to_command(np.array([1.0, 1.0])), (0.47, 3.0))
    assert_allclose(env.action_to_command(np.array([-1.0, -1.0])), (-0.47, -3.0))
    assert_allclose(env.action_to_command(np.array([0.0, 0.0])), (0.0, 0.0))
    assert_allclose(env.action_to_command(np.array([2.0, -7.0])), (0.47, -3.0))
    assert_allclose(env.command_to_action(0.235, -1.5), [0.5, -0.5])
    assert env.brake_limit == 3.0
    physical = ConeTrackEnv(action="physical")
    assert_allclose(physical.action_space.low, [-0.47, -10.0])
    assert_allclose(physical.action_space.high, [0.47, 3.0])
    assert_allclose(physical.action_to_command(np.array([0.2, -12.0])), (0.2, -10.0), rtol=1e-6)
    assert_allclose(physical.command_to_action(0.1, -5.0), [0.1, -5.0])
    assert physical.brake_limit == 10.0
    env.reset(seed=0)
    with pytest.raises(ValueError, match="finite"):
        env.step(np.array([np.nan, 0.0], dtype=np.float32))


def test_reward_terms_sum_and_progress() -> None:
    """Driving straight ahead: progress ~ distance, time term -dt per step, sum is the reward."""
    env = ConeTrackEnv(sensors="ideal")
    env.reset(seed=0)
    total_progress = 0.0
    for _ in range(50):
        _, reward, _, _, info = env.step(np.array([0.0, 1.0], dtype=np.float32))
        terms = info["reward_terms"]
        assert reward == pytest.approx(sum(terms.values()))
        assert terms["time"] == pytest.approx(-0.02)
        total_progress += terms["progress"]
    # 1 s at 3 m/s^2 from rest: 1.5 m (the kinematic start loses a little).
    assert total_progress == pytest.approx(1.5, rel=0.05)


def test_off_track_terminates_with_penalty() -> None:
    """Full lock into the infield ends the episode as off_track with its penalty."""
    env = ConeTrackEnv(sensors="ideal")
    env.reset(seed=0)
    for _ in range(1000):
        _, _, terminated, truncated, info = env.step(np.array([1.0, 0.6], dtype=np.float32))
        if terminated or truncated:
            break
    assert terminated and END_REASONS[info["end_reason"]] == "off_track"
    assert info["reward_terms"]["off_track"] == -10.0


def test_reset_options_and_bad_config() -> None:
    """reset(options) switches track; unknown keys and values are refused with the allowed list."""
    env = ConeTrackEnv()
    env.reset(seed=1, options={"track": "skidpad", "sensors": "ideal"})
    assert env.loop.track.name == "skidpad"
    with pytest.raises(ValueError, match="allowed"):
        env.reset(options={"weather": "rain"})
    with pytest.raises(ValueError, match="allowed keys"):
        ConeTrackEnv(wind=3)
    with pytest.raises(ValueError, match="allowed"):
        ConeTrackEnv(sensors="lidar9000")
    with pytest.raises(ValueError, match="whole multiple"):
        EnvConfig(control_rate=30.0)


def test_time_limit_truncates() -> None:
    """A 1 s limit truncates after 50 steps at 50 Hz."""
    env = ConeTrackEnv(time_limit=1.0, sensors="ideal")
    env.reset(seed=0)
    steps = 0
    while True:
        _, _, terminated, truncated, info = env.step(np.zeros(2, dtype=np.float32))
        steps += 1
        if truncated or terminated or steps > 100:
            break
    assert steps == 50 and not terminated and END_REASONS[info["end_reason"]] == "time_limit"


@pytest.mark.parametrize("mode", ["sync", "async"])
def test_make_vec(mode: str) -> None:
    """gymnasium.make_vec runs two envs in sync and async modes."""
    vec = gym.make_vec(envs.ENV_ID, num_envs=2, vectorization_mode=mode, sensors="ideal")
    try:
        obs, _ = vec.reset(seed=[1, 2])
        assert obs.shape == (2, 8 + 5 * 32)
        for _ in range(5):
            obs, reward, _, _, _ = vec.step(np.zeros((2, 2), dtype=np.float32))
        assert reward.shape == (2,)
        assert np.all(np.isfinite(obs))
    finally:
        vec.close()


def _shape_of(value: object) -> object:
    """The keys and value types of an info, recursively (lists as one type)."""
    if isinstance(value, dict):
        return {k: _shape_of(v) for k, v in value.items()}
    return type(value)


@pytest.mark.parametrize("localization", ["fused", "raw", "truth", "cones"])
def test_info_has_one_shape_from_reset_to_every_step(localization: str) -> None:
    """Every info key keeps its type from reset() on (gymnasium's vector envs
    stack them key by key); before the first broadcast the localization error
    is inf, not None."""
    env = ConeTrackEnv(track="acceleration", localization=localization, info="full")
    _, info = env.reset(seed=0)
    shape = _shape_of(info)
    if localization != "truth":  # truth broadcasts at t = 0
        assert info["localization_error"] == {"position_m": math.inf, "yaw_rad": math.inf}
    for _ in range(3):
        _, _, _, _, info = env.step(np.array([0.0, 0.5], dtype=np.float32))
        assert _shape_of(info) == shape
    assert info["localization_error"]["position_m"] < 0.2


def test_vector_env_with_episodes_ending_apart() -> None:
    """A sync vector env whose sub-envs end at different steps autoresets one
    and stacks the infos of a fresh and a running episode (this raised in
    gymnasium's info stacking when the fresh one's localization error was None)."""
    vec = gym.vector.SyncVectorEnv(
        [
            lambda: gym.make(envs.ENV_ID, track="acceleration", time_limit=0.1, info="full"),
            lambda: gym.make(envs.ENV_ID, track="acceleration", time_limit=1.0, info="full"),
        ]
    )
    try:
        vec.reset(seed=0)
        ended = []
        for _ in range(8):
            _, _, terminated, truncated, info = vec.step(np.zeros((2, 2), dtype=np.float32))
            ended.append((terminated | truncated).tolist())
        assert ended[4] == [True, False]  # 0.1 s = 5 steps at 50 Hz
        # The fresh episode has no broadcast yet (inf), the running one has.
        error = info["localization_error"]["position_m"]
        assert error.shape == (2,) and error[0] == math.inf and math.isfinite(error[1])
    finally:
        vec.close()


def test_step_needs_reset_and_an_action_of_two() -> None:
    """step() before reset() and an action of another shape are refused by name."""
    env = ConeTrackEnv(track="acceleration")
    with pytest.raises(gym.error.ResetNeeded, match="reset"):
        env.step(np.zeros(2, dtype=np.float32))
    env.reset(seed=0)
    for bad in (np.zeros(3), np.zeros((1, 2))):
        with pytest.raises(ValueError, match=r"action must have shape \(2,\)"):
            env.step(bad)
    _, _, _, _, info = env.step([0.0, 0.0])  # a list of two is an action
    assert all(math.copysign(1.0, v) == 1.0 for k, v in info["reward_terms"].items() if v == 0.0)


def test_human_mode_without_pygame_names_the_extra(monkeypatch: pytest.MonkeyPatch) -> None:
    """Without pygame, asking for human rendering fails at once, naming the extra."""
    import sys

    monkeypatch.setitem(sys.modules, "pygame", None)  # import pygame -> ImportError
    with pytest.raises(gym.error.DependencyNotInstalled, match=r"conesim\[render\]"):
        ConeTrackEnv(render_mode="human")


def test_human_mode_without_a_display_says_so(monkeypatch: pytest.MonkeyPatch) -> None:
    """On Linux with no display (and no SDL driver chosen) a window would show nothing:
    refused when made, pointing at rgb_array; a chosen driver is trusted."""
    pytest.importorskip("pygame")
    monkeypatch.setattr("sys.platform", "linux")
    for name in ("DISPLAY", "WAYLAND_DISPLAY", "SDL_VIDEODRIVER"):
        monkeypatch.delenv(name, raising=False)
    with pytest.raises(gym.error.DependencyNotInstalled, match=r"no display.*rgb_array"):
        ConeTrackEnv(render_mode="human")
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    assert ConeTrackEnv(render_mode="human").render_mode == "human"


def test_reset_options_last_one_episode_and_bad_ones_change_nothing() -> None:
    """Options apply to one episode; a bad option leaves the env usable and unchanged."""
    env = ConeTrackEnv(sensors="ideal")
    env.reset(seed=3, options={"track": "skidpad"})
    assert env.loop.track.name == "skidpad"
    env.reset(seed=3)
    assert env.loop.track.name == "trackdrive"
    with pytest.raises(Exception, match="monza"):
        env.reset(seed=3, options={"track": "monza"})
    obs, _ = env.reset(seed=3)
    fresh, _ = ConeTrackEnv(sensors="ideal").reset(seed=3)
    assert obs.tobytes() == fresh.tobytes()


def test_reset_without_seed_continues_the_rng_reproducibly() -> None:
    """reset(seed=s) then reset() twice gives the same episodes in two envs."""
    runs = []
    for _ in range(2):
        env = ConeTrackEnv()
        env.reset(seed=11)
        seeds = []
        for _ in range(2):
            env.reset()
            seeds.append(env.loop.world.seed)
        runs.append(seeds)
    assert runs[0] == runs[1] and runs[0][0] != runs[0][1]


def test_env_time_limit_comes_before_the_registered_step_cap() -> None:
    """With 2 laps the episode may run past 90 s: gymnasium's cap is only a backstop."""
    env = gym.make(envs.ENV_ID, laps=2, sensors="ideal", time_limit=100.0, control_rate=10.0)
    env.reset(seed=0)
    steps = 0
    while True:
        _, _, terminated, truncated, info = env.step(np.zeros(2, dtype=np.float32))
        steps += 1
        if terminated or truncated:
            break
    # Standing still: stuck at the 15 s grace ends it (terminated), long before any cap.
    assert END_REASONS[info["end_reason"]] == "stuck" and steps == 150
    env.close()


def test_localization_error_in_every_mode() -> None:
    """info carries the broadcast pose error in raw, fused and truth modes."""
    for mode in ("raw", "fused", "truth"):
        env = ConeTrackEnv(localization=mode, info="full")
        env.reset(seed=0)
        for _ in range(20):
            _, _, _, _, info = env.step(np.array([0.0, 0.5], dtype=np.float32))
        err = info["localization_error"]
        assert err is not None
        assert err["position_m"] < (1e-9 if mode == "truth" else 0.2)


def test_autopilot_expert_drives_raw_localization_cautiously() -> None:
    """Default settings with fused localization; the cautious preset (6 m/s^2
    lateral with no downforce share, in the plan and the command's ellipse,
    6 m/s^2 braking, 15 m/s) in an episode with raw localization, also when a reset
    option picks it; settings given to the expert are kept."""
    env = ConeTrackEnv(track="autocross", action="physical")
    _, info = env.reset(seed=0)
    expert = AutopilotExpert(env)
    expert.reset(info)
    assert expert.autopilot is not None and expert.autopilot.config == AutopilotConfig()
    _, info = env.reset(seed=0, options={"localization": "raw"})
    expert.reset(info)
    assert expert.autopilot.config == AutopilotConfig.cautious()
    profile = expert.autopilot.config.speed_profile
    control = expert.autopilot.config.speed_control
    assert (profile.a_lat_max, profile.a_lat_aero, profile.a_brake, profile.v_max) == (
        6.0, 0.0, 6.0, 15.0,
    )  # fmt: skip
    assert (control.lateral_grip, control.grip_aero) == (6.0, 0.0)
    given = AutopilotConfig.from_dict({"speed_window": 0.2})
    kept = AutopilotExpert(env, given)
    kept.reset(info)
    assert kept.autopilot is not None and kept.autopilot.config == given


def test_autopilot_expert_completes_a_lap_through_the_env() -> None:
    """The expert, through the env's public interface only, drives the
    acceleration run clean, within 1 % of the loop's own autopilot run of the
    same seed (the env's float32 actions round its commands)."""
    from conesim.envs.runner import run_scenario

    env = ConeTrackEnv(track="acceleration", sensors="ideal", action="physical")
    _, info = env.reset(seed=4)
    expert = AutopilotExpert(env)
    action = expert.reset(info)
    while True:
        _, _, terminated, truncated, info = env.step(action)
        if terminated or truncated:
            break
        action = expert(info)
    assert END_REASONS[info["end_reason"]] == "laps_completed"
    assert info["cones_down_or_out"] == 0 and info["off_track_events"] == 0
    assert expert.output is not None  # the step before the last (the last one ended it)
    assert expert.output.command.stamp == pytest.approx(info["t"] - 1.0 / env.config.control_rate)
    direct = run_scenario("acceleration", sensors="ideal", seed=4)
    assert direct.lap_times_s[0] == pytest.approx(info["lap_time"], rel=0.01)


def test_uncertainty_before_the_filter_has_an_estimate() -> None:
    """Dict mode: pos_std and yaw_std are their bounds (1000 m, pi) until the
    EKF initialises, then its 1-sigma figures; 0 in truth and raw mode. The
    vector mode says the same with its validity flag, the uncertainties 0."""
    env = ConeTrackEnv(localization="fused", observation="dict")
    obs, _ = env.reset(seed=0)
    assert_allclose(obs["ego"][4:6], [1e3, math.pi], rtol=1e-6)
    while env.loop.localizer.estimate(env.loop.time) is None:
        obs, _, _, _, _ = env.step(np.zeros(2, dtype=np.float32))
    assert 0.0 < obs["ego"][4] < 0.1 and 0.0 < obs["ego"][5] < 0.1
    for mode in ("truth", "raw"):
        obs, _ = ConeTrackEnv(localization=mode, observation="dict").reset(seed=0)
        assert_allclose(obs["ego"][4:6], [0.0, 0.0])
    vec = ConeTrackEnv(localization="fused")
    obs, _ = vec.reset(seed=0)
    assert_allclose(obs[4:7], [0.0, 0.0, 0.0])  # pose_valid, pos_std, yaw_std
    while vec.loop.localizer.estimate(vec.loop.time) is None:
        obs, _, _, _, _ = vec.step(np.zeros(2, dtype=np.float32))
    # rtk: 1-sigma of a few cm (/ 1 m) and a few mrad (/ 0.1 rad)
    assert obs[4] == 1.0 and 0.0 < obs[5] < 0.1 and 0.0 < obs[6] < 0.5


def test_dict_pose_in_every_localization_mode() -> None:
    """Dict mode's pose is what localization holds in every mode: the EKF's
    estimate (fused), the frame tree's last broadcast (raw, truth; truth
    exactly the antenna's pose at the last 20 Hz broadcast); invalid and zero
    before there is one."""
    for mode in ("truth", "raw", "fused"):
        env = ConeTrackEnv(localization=mode, observation="dict")
        obs, _ = env.reset(seed=0)
        assert obs["pose_valid"][0] == (1.0 if mode == "truth" else 0.0), mode
        for _ in range(50):  # 1 s at 50 Hz, accelerating
            obs, _, _, _, _ = env.step(np.array([0.0, 0.5], dtype=np.float32))
        assert env.observation_space.contains(obs)
        assert obs["pose_valid"][0] == 1.0
        antenna = env.loop.world.antenna_pose
        error = math.hypot(obs["pose"][0] - antenna.x, obs["pose"][1] - antenna.y)
        # 1 s, broadcast every 50 ms = every 2.5 control steps: the truth
        # broadcast is this step's (t = 1.0 s is on the grid).
        assert error < {"truth": 1e-5, "raw": 0.2, "fused": 0.05}[mode], (mode, error)
        cov = obs["pose_covariance"]
        if mode == "fused":
            assert 0.0 < cov[0, 0] < 0.01 and cov[2, 2] > 0.0
        else:
            assert not cov.any()
        env.close()


def test_dict_cones_age_is_the_detections_latency_plus_time_since_arrival() -> None:
    """Dict mode's ``cones_age``: 10 Hz scans observed at 50 Hz. ideal (no
    latency, a scan at t = 0): 0, 0.02, ..., 0.08 s, then the next scan.
    rtk (fssim's 0.2 s LiDAR latency): 1000 s (no detection yet) until the
    first scan arrives at t = 0.2 s, then 0.2, 0.22, ..., 0.28 s."""
    expected = {
        "ideal": [0.0, 0.02, 0.04, 0.06, 0.08] * 3,
        "rtk": [1e3] * 10 + [0.2, 0.22, 0.24, 0.26, 0.28],
    }
    for sensors, ages in expected.items():
        env = ConeTrackEnv(sensors=sensors, observation="dict")
        obs, _ = env.reset(seed=0)
        seen = [float(obs["cones_age"][0])]
        for _ in range(len(ages) - 1):
            obs, _, _, _, _ = env.step(np.array([0.0, 0.3], dtype=np.float32))
            seen.append(float(obs["cones_age"][0]))
        assert_allclose(seen, ages, atol=1e-6, err_msg=sensors)
        assert env.observation_space.contains(obs)
        env.close()


def test_config_types_numpy_integers_yes_bools_and_strings_no() -> None:
    """A numpy integer is an integer (parameter sweeps); a bool is not a lap
    count, a string is not a flag, a list is not a set of reward weights."""
    cfg = EnvConfig(laps=np.int64(2), max_cones=np.int64(16), control_rate=np.float32(25.0))
    assert (cfg.laps, cfg.max_cones, cfg.substeps) == (2, 16, 8)
    # Stored as plain Python values: a float32 rate would make the clock float32.
    assert type(cfg.laps) is int and type(cfg.control_rate) is float
    assert EnvConfig(rewards={"time": -0.5}).rewards.time == -0.5
    from conesim.tracks import load_track

    source = load_track("autocross").source
    assert source is not None
    assert EnvConfig(track=source).track == str(source)  # a path is a track file
    bad = {
        "laps": True,
        "terminate_off_track": "no",
        "rewards": [1, 2],
        "track": 5,
        "sensors": 5,
        "time_limit": "60",
    }
    for key, value in bad.items():
        with pytest.raises(ValueError, match=f"EnvConfig.{key}"):
            EnvConfig.from_dict({key: value})


@pytest.mark.parametrize(
    "start", [(0.0, 0.0), "abc", "123", (0.0, math.nan, 0.0), 5, (0.0, 30.0, 0.0)]
)
def test_bad_start_pose_option_is_named(start: object) -> None:
    """Not three finite numbers, or off the track (trackdrive, 30 m north of
    the start line: the infield): refused, naming the option; the env keeps
    its episode."""
    env = ConeTrackEnv()
    env.reset(seed=0)
    before = env.loop
    with pytest.raises(ValueError, match="reset option start_pose"):
        env.reset(seed=0, options={"start_pose": start})
    assert env.loop is before


def test_a_start_pose_beyond_the_end_of_an_open_lane_is_off_the_track() -> None:
    """On the acceleration lane's axis, 20 m behind its first point and
    10,000 km past its last (0.0 m off its line, yet on no track), the car is
    off the track; its own start pose is not."""
    env = ConeTrackEnv(track="acceleration")
    env.reset(seed=0)
    for start in ((-20.0, 0.0, 0.0), (1.0e7, 0.0, 0.0)):
        with pytest.raises(ValueError, match="puts the car off the track"):
            env.reset(options={"start_pose": start})
    env.reset(options={"start_pose": (-2.0, 0.0, 0.0)})


def test_a_refused_reset_leaves_the_random_generator_as_it_was() -> None:
    """After a refused reset (an off-track start), reset() without a seed
    gives the episode it would have given."""
    env = ConeTrackEnv(track="acceleration")
    env.reset(seed=0)
    expected, _ = env.reset()
    env.reset(seed=0)
    with pytest.raises(ValueError, match="off the"):
        env.reset(options={"start_pose": (0.0, 30.0, 0.0)})
    with pytest.raises(ValueError, match=r"reset option start_pose.*latitude"):
        env.reset(seed=5, options={"start_pose": (0.0, 1.0e8, 0.0)})  # beyond the pole
    again, _ = env.reset()
    assert np.array_equal(again, expected)


def test_resets_on_one_track_reuse_its_world_and_another_track_gets_a_new_one() -> None:
    """Resets with the env's track reset its world (the same object) and give
    a new env's episodes; a reset to another track builds a new world, and
    one back to the env's track another."""
    env = ConeTrackEnv(sensors="ideal", localization="truth", info="full")
    actions = [np.array([0.3 * math.sin(k / 20), 1.0], dtype=np.float32) for k in range(120)]

    def run(e: ConeTrackEnv, seed: int, options: dict[str, object] | None = None) -> list[object]:
        obs, info = e.reset(seed=seed, options=options)
        out: list[object] = [obs.tobytes(), repr(info["truth"])]
        for action in actions:
            obs, reward, terminated, truncated, info = e.step(action)
            out += [obs.tobytes(), reward, terminated, truncated, repr(info["truth"])]
        return out

    run(env, 0)
    world = env.loop.world
    start = {"start_pose": (float(world.track.start_pose.x) + 3.0, 0.2, 0.05)}
    for seed, options in [(1, None), (2, start), (3, None)]:
        got = run(env, seed, options)
        assert env.loop.world is world
        assert got == run(ConeTrackEnv(sensors="ideal", localization="truth", info="full"),
                          seed, options)  # fmt: skip
    run(env, 4, {"track": "skidpad"})
    assert env.loop.world is not world and env.loop.track.name == "skidpad"
    skidpad = env.loop.world
    got = run(env, 5)
    assert env.loop.world is not world and env.loop.world is not skidpad
    assert env.loop.track.name == "trackdrive"
    assert got == run(ConeTrackEnv(sensors="ideal", localization="truth", info="full"), 5)
