"""A smoke run of the training baseline (examples/train_ppo.py): a few thousand
steps of PPO, then the held-out evaluation on two tracks. It checks what the
run writes, not how well the policy drives (docs/TRAINING.md has
the real run's figures). Skipped without the rl extra."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

REPO = Path(__file__).resolve().parents[2]
SCRIPT = REPO / "examples" / "train_ppo.py"
STEPS = 2048


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("ppo")
    done = subprocess.run(
        [sys.executable, str(SCRIPT), "--out", str(out), "--minutes", "0",
         "--steps", str(STEPS), "--n-steps", "256", "--batch-size", "128",
         "--n-envs", "2", "--vec", "subproc", "--eval-tracks", "2",
         "--train-seeds", "0", "50", "--train-env", "stuck_time=4",
         "--train-env", "stuck_grace=6"],
        capture_output=True, text=True, check=False, timeout=600, cwd=REPO,
    )  # fmt: skip
    assert done.returncode == 0, done.stdout + done.stderr
    return out


@pytest.mark.slow
def test_the_json_has_the_figures(run: Path) -> None:
    summary = json.loads((run / "results.json").read_text(encoding="utf-8"))
    evaluation, training = summary["evaluation"], summary["training"]
    assert 0.0 <= evaluation["laps_completed_share"] <= 1.0
    assert np.isfinite(evaluation["return_mean"])
    assert 0.0 <= evaluation["progress_share_mean"] <= 1.0
    assert evaluation["tracks"] == 2
    per_track = evaluation["per_track"]
    assert [t["seed"] for t in per_track] == evaluation["seeds"]
    assert all(t["seed"] >= 50 for t in per_track)  # none of the training seeds
    for track in per_track:  # the autopilot laps every held-out track
        assert 10.0 < track["autopilot_lap_time_s"] < 60.0
        assert (track["lap_time_s"] is None) == (not track["lap_completed"])
    assert STEPS <= training["steps"] < STEPS + 512
    assert training["steps_per_s"] > 0
    assert summary["settings"]["ppo"]["n_steps"] == 256
    # the training envs' own rules are recorded; the evaluation's env keeps the defaults
    train_env = {"physics_rate": 100.0, "stuck_time": 4, "stuck_grace": 6}
    assert summary["settings"]["train_env"] == train_env
    assert "stuck_time" not in summary["settings"]["env"]
    assert "physics_rate" not in summary["settings"]["env"]
    lines = (run / "curve.csv").read_text(encoding="utf-8").splitlines()
    assert lines[0].split(",")[:3] == ["step", "return", "progress_m"]
    assert training["episodes"] == len(lines) - 1 > 0


@pytest.mark.slow
def test_the_learning_curve_is_a_picture(run: Path) -> None:
    picture = (run / "learning_curve.png").read_bytes()
    assert picture.startswith(b"\x89PNG\r\n\x1a\n")
    assert len(picture) > 10_000  # four panels drawn, not an empty canvas


@pytest.mark.slow
def test_the_policy_loads_and_drives(run: Path) -> None:
    import gymnasium as gym
    from stable_baselines3 import PPO

    import conesim

    model = PPO.load(run / "policy.zip", device="cpu")
    settings = json.loads((run / "results.json").read_text(encoding="utf-8"))["settings"]["env"]
    assert settings["path_preview"] == 10  # the baseline's observation has the path ahead
    settings.update(track="random", track_seeds=(1000, 1010))
    env = gym.make(conesim.ENV_ID, **settings)
    assert env.observation_space.shape == model.observation_space.shape == (8 + 5 * 32 + 20,)
    obs, _ = env.reset(seed=3)
    for _ in range(20):
        action, _ = model.predict(obs, deterministic=True)
        assert env.action_space.contains(np.clip(action, -1, 1).astype(np.float32))
        assert action.shape == env.action_space.shape
        obs, reward, terminated, truncated, _ = env.step(action)
        assert np.isfinite(reward)
        if terminated or truncated:
            break
    env.close()


@pytest.mark.parametrize(
    ("flag", "said"),
    [
        ("stuck_time", "expected KEY=VALUE"),
        ("rewards={time: [", "--train-env 'rewards={time: ['"),
        ("stuck_tme=3", "unknown keys ['stuck_tme']"),
        ("stuck_time=-1", "EnvConfig.stuck_time must be > 0 [s], got -1"),
    ],
)
def test_a_bad_training_env_setting_is_one_line_and_exit_2(
    flag: str, said: str, tmp_path: Path
) -> None:
    out = tmp_path / "ppo"
    done = subprocess.run(
        [sys.executable, str(SCRIPT), "--train-env", flag, "--steps", "1", "--out", str(out)],
        capture_output=True, text=True, check=False, timeout=120, cwd=REPO,
    )  # fmt: skip
    assert done.returncode == 2
    assert said in done.stderr.strip().splitlines()[-1]  # one line says it (after any usage)
    assert "Traceback" not in done.stderr
    assert not out.exists()  # nothing written
