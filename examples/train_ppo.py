"""Train a PPO policy on generated tracks and test it on tracks it never saw.

The training baseline of the env (README, "Training a policy"):
stable-baselines3's PPO with its ``MlpPolicy`` drives
``conesim/ConeTrack-v0`` with ``track="random"`` on the training seeds
(``--train-seeds``, default 0-199), then the deterministic policy drives one
lap on each of ``--eval-tracks`` held-out generated tracks (seeds from
``--eval-seed0`` on, default 1000-1019), and the autopilot
(``envs.runner.run_scenario``) drives the same tracks for its lap time.

Usage (the ``rl`` extra, ``make rl``)::

    .venv/bin/python examples/train_ppo.py --minutes 26 --out runs/ppo

Writes to ``--out``:

- ``policy.zip``: the trained PPO model (``PPO.load(path).predict(obs)``;
  the env's vector observation needs no normalisation wrapper).
- ``learning_curve.png``: episode return, progress, laps and mean speed of
  the training episodes over the steps, raw and smoothed.
- ``curve.csv``: the same, one training episode a line.
- ``results.json``: the evaluation's figures (share of laps completed, lap
  time over the autopilot's, return), per track and in all, the training's
  steps, minutes and steps/s, and every hyperparameter.

The settings, and why (the defaults are the measured baseline):

- the env: ``sensors="ideal"``, ``localization="truth"`` (the policy sees
  the detected cones in the car's frame either way; these make a step about
  4x cheaper than the default rtk + EKF, so 30 minutes give 4x the driving),
  ``control_rate=20`` (an action every 50 ms: one step of the network buys
  2.5x the driving of a 50 Hz step), and ``path_preview=10`` 3 m apart (the
  global path's next 30 m in the car's frame, ``envs.observation``): with
  the cones of the last scan alone (and seeds 0-999, ``gamma`` 0.99,
  ``ent_coef`` 0), 1 held-out lap in 20 after 26 min; with all of these,
  3 and 6 in 20 (two PPO seeds) in the same time with half the steps
  (docs/TRAINING.md).
  ``--path-preview 0`` drops it. The env's default reward (+1 per metre, -1
  per second, the FS penalties) and its normalised vector observation.
- the training envs alone run the physics at 100 Hz (``TRAIN_ENV_SETTINGS``;
  the held-out evaluation keeps 200 Hz): the autopilot's laps on held-out
  tracks differ by at most 0.02 s, and a step costs about 0.7x (docs/TRAINING.md).
- ``--train-seeds`` 0-199: 200 tracks (about 3,000 corners) are variety
  enough, and the env keeps them all loaded, so after the first visits a
  reset costs 0.06 s, not the 0.3-0.5 s of making and deriving a new track
  (with 1,000 seeds most of a 26-minute run's resets were first visits).
- ``VecNormalize(norm_obs=False, norm_reward=True)``: the observation is of
  order 1 already; scaling the return helps the value function (a lap is
  worth about 300).
- PPO: ``n_steps`` 1024 per env, ``batch_size`` 256, ``n_epochs`` 10,
  ``learning_rate`` 3e-4, ``gamma`` 0.995 (at 20 Hz a 10 s horizon: a
  corner 60 m on is within it at 6 m/s), ``gae_lambda`` 0.95,
  ``clip_range`` 0.2, ``ent_coef`` 0.005 (so the policy does not settle
  early), ``MlpPolicy`` 2 x 64 tanh (the defaults of SB3 but for
  ``n_steps``, ``batch_size``, ``gamma`` and ``ent_coef``), ``log_std_init``
  -0.5 (less steering jitter at the start).
- ``--n-envs`` 2, stepped in this process (``DummyVecEnv``; ``--vec subproc``
  puts each in a ``SubprocVecEnv`` worker), torch on one thread. On the
  2-core machine, loaded by other work, 2 envs in this process ran 425
  steps/s, 2 subprocess workers 384 and 1 env 278 (12 k steps each, PPO's
  updates included): the network's forward pass and the updates share the
  cores with the workers, so the workers buy nothing here.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from importlib.metadata import version
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from matplotlib.figure import Figure

import conesim
from conesim.envs.cone_track_env import END_REASONS
from conesim.envs.config import EnvConfig
from conesim.envs.dataclass_io import FieldError
from conesim.envs.runner import run_scenario
from conesim.envs.yaml_io import parse_value
from conesim.tracks import GeneratedTrack, TrackGenerationError, load_track

try:
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.callbacks import BaseCallback
    from stable_baselines3.common.vec_env import (
        DummyVecEnv,
        SubprocVecEnv,
        VecEnv,
        VecMonitor,
        VecNormalize,
    )
except ImportError as err:  # pragma: no cover - the rl extra is optional
    raise SystemExit(
        f"train_ppo needs the rl extra ({err}): make rl, or pip install torch==2.13.0 "
        "then pip install -e '.[rl]' (README, 'Training a policy')"
    ) from err

ENV_SETTINGS: dict[str, Any] = {
    "sensors": "ideal",
    "localization": "truth",
    "control_rate": 20.0,
    "path_preview": 10,
    "path_preview_step": 3.0,
}
"""The env's settings for training and evaluation (the module docstring says why;
``--path-preview`` changes the preview's points, 0 for none)."""

TRAIN_ENV_SETTINGS: dict[str, Any] = {"physics_rate": 100.0}
"""The training envs' own settings, under ``--train-env`` (the evaluation keeps the
env's 200 Hz physics): at 100 Hz the car laps held-out tracks within 0.02 s of
200 Hz, and a 20 Hz step costs 5 physics steps instead of 10."""

PPO_SETTINGS: dict[str, Any] = {
    "n_steps": 1024,
    "batch_size": 256,
    "n_epochs": 10,
    "learning_rate": 3e-4,
    "gamma": 0.995,
    "gae_lambda": 0.95,
    "clip_range": 0.2,
    "ent_coef": 0.005,
    "policy_kwargs": {"net_arch": [64, 64], "log_std_init": -0.5},
}
"""PPO's hyperparameters (``--n-steps``, ``--batch-size``, ``--gamma`` and
``--ent-coef`` change theirs)."""

CURVE_FIELDS = ("step", "return", "progress_m", "laps", "speed_mps", "end_reason")


def make_env(seeds: tuple[int, int], rank: int, settings: dict[str, Any]) -> Callable[[], gym.Env]:
    """A factory of one training env (for the vector env's workers)."""

    def factory() -> gym.Env:
        env = gym.make(conesim.ENV_ID, track="random", track_seeds=seeds, **settings)
        env.reset(seed=10_000 + rank)
        return env

    return factory


class CurveRecorder(BaseCallback):
    """Records every finished training episode and stops at the time budget."""

    def __init__(self, budget_s: float | None, print_every_s: float = 30.0) -> None:
        super().__init__()
        self.budget_s = budget_s
        self.print_every_s = print_every_s
        self.rows: list[dict[str, float]] = []
        self.t0 = time.perf_counter()
        self._last_print = self.t0

    def _on_training_start(self) -> None:
        self.t0 = time.perf_counter()
        self._last_print = self.t0

    def _on_step(self) -> bool:
        for done, info in zip(self.locals["dones"], self.locals["infos"], strict=True):
            if not done or "episode" not in info:
                continue
            t = float(info["t"])
            self.rows.append(
                {
                    "step": float(self.num_timesteps),
                    "return": float(info["episode"]["r"]),
                    "progress_m": float(info["progress_m"]),
                    "laps": float(info["laps_completed"]),
                    "speed_mps": float(info["progress_m"]) / t if t > 0 else 0.0,
                    "end_reason": float(info["end_reason"]),
                }
            )
        now = time.perf_counter()
        if now - self._last_print >= self.print_every_s and self.rows:
            self._last_print = now
            last = self.rows[-50:]
            print(
                f"  {self.num_timesteps:>8d} steps, {now - self.t0:6.0f} s, "
                f"{self.num_timesteps / (now - self.t0):6.0f} steps/s: "
                f"return {np.mean([r['return'] for r in last]):7.1f}, "
                f"progress {np.mean([r['progress_m'] for r in last]):6.1f} m, "
                f"laps {np.mean([r['laps'] for r in last]):4.2f}, "
                f"speed {np.mean([r['speed_mps'] for r in last]):5.2f} m/s "
                f"(last {len(last)} episodes)",
                flush=True,
            )
        return self.budget_s is None or now - self.t0 < self.budget_s


@dataclass
class TrackResult:
    """One held-out track: the policy's lap and the autopilot's."""

    seed: int
    length_m: float
    lap_completed: bool
    end_reason: str
    return_: float
    progress_m: float
    lap_time_s: float | None
    autopilot_lap_time_s: float | None
    cones_down_or_out: int
    off_track_events: int

    @property
    def ratio(self) -> float | None:
        if self.lap_time_s is None or not self.autopilot_lap_time_s:
            return None
        return self.lap_time_s / self.autopilot_lap_time_s

    def to_json(self) -> dict[str, Any]:
        return {
            "seed": self.seed,
            "length_m": round(self.length_m, 1),
            "lap_completed": self.lap_completed,
            "end_reason": self.end_reason,
            "return": round(self.return_, 2),
            "progress_m": round(self.progress_m, 1),
            "lap_time_s": self.lap_time_s,
            "autopilot_lap_time_s": self.autopilot_lap_time_s,
            "lap_time_ratio": None if self.ratio is None else round(self.ratio, 3),
            "cones_down_or_out": self.cones_down_or_out,
            "off_track_events": self.off_track_events,
        }


def held_out_tracks(seed0: int, count: int, exclude: tuple[int, int]) -> list[GeneratedTrack]:
    """``count`` generated tracks from seed ``seed0`` on, none of the training
    seeds, skipping seeds the generator gives up on."""
    tracks: list[GeneratedTrack] = []
    seed = seed0
    while len(tracks) < count:
        if not exclude[0] <= seed < exclude[1]:
            track = GeneratedTrack(seed)
            try:
                load_track(track)
            except TrackGenerationError:
                pass
            else:
                tracks.append(track)
        seed += 1
    return tracks


def evaluate(
    model: PPO, tracks: Sequence[GeneratedTrack], settings: dict[str, Any]
) -> list[TrackResult]:
    """One lap of the deterministic policy, then the autopilot, on each track."""
    results = []
    env = gym.make(conesim.ENV_ID, track=tracks[0], **settings)
    for track in tracks:
        obs, info = env.reset(seed=0, options={"track": track})
        total = 0.0
        while True:
            action, _ = model.predict(obs, deterministic=True)
            obs, reward, terminated, truncated, info = env.step(action)
            total += float(reward)
            if terminated or truncated:
                break
        done = int(info["laps_completed"]) >= 1
        auto = run_scenario(
            track,
            laps=1,
            seed=0,
            sensors=settings["sensors"],
            localization=settings["localization"],
            control_rate=settings["control_rate"],
        )
        results.append(
            TrackResult(
                seed=track.seed,
                length_m=float(load_track(track).length_m),
                lap_completed=done,
                end_reason=END_REASONS[int(info["end_reason"])],
                return_=total,
                progress_m=float(info["progress_m"]),
                lap_time_s=round(float(info["lap_time"]), 2) if done else None,
                autopilot_lap_time_s=(round(auto.lap_times_s[0], 2) if auto.lap_times_s else None),
                cones_down_or_out=int(info["cones_down_or_out"]),
                off_track_events=int(info["off_track_events"]),
            )
        )
        print(f"  track {track.seed}: {results[-1].to_json()}", flush=True)
    env.close()
    return results


def smooth(values: Sequence[float], window: int) -> np.ndarray:
    """The running mean over the last ``window`` values (fewer at the start)."""
    x = np.asarray(values, dtype=float)
    if x.size == 0:
        return x
    c = np.cumsum(np.insert(x, 0, 0.0))
    idx = np.arange(1, x.size + 1)
    lo = np.maximum(idx - window, 0)
    return (c[idx] - c[lo]) / (idx - lo)


def plot_curve(rows: Sequence[dict[str, float]], path: Path, title: str) -> None:
    """The learning curve: four panels over the training steps."""
    fig = Figure(figsize=(10, 6.5))
    axes = fig.subplots(2, 2, sharex=True)
    panels = (
        ("return", "episode return"),
        ("progress_m", "progress [m]"),
        ("laps", "laps completed"),
        ("speed_mps", "mean speed [m/s]"),
    )
    steps = np.array([r["step"] for r in rows])
    window = max(1, len(rows) // 20)
    for ax, (key, label) in zip(axes.flat, panels, strict=True):
        values = [r[key] for r in rows]
        ax.plot(steps, values, ".", ms=2, alpha=0.3, color="tab:blue")
        ax.plot(steps, smooth(values, window), "-", lw=2, color="tab:red")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    for ax in axes[1]:
        ax.set_xlabel("training steps")
    fig.suptitle(f"{title} (red: mean of the last {window} episodes)")
    fig.tight_layout()
    fig.savefig(path, dpi=80)


def rising(rows: Sequence[dict[str, float]], key: str = "return") -> dict[str, float | bool]:
    """The smoothed curve's first and last fifth, and whether it rose."""
    values = [r[key] for r in rows]
    if len(values) < 10:
        return {"first_fifth": math.nan, "last_fifth": math.nan, "rises": False}
    fifth = len(values) // 5
    first, last = float(np.mean(values[:fifth])), float(np.mean(values[-fifth:]))
    return {"first_fifth": round(first, 2), "last_fifth": round(last, 2), "rises": last > first}


def load_average() -> str:
    try:
        return subprocess.run(["uptime"], capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return " ".join(f"{x:.2f}" for x in os.getloadavg())


def parse_args(argv: Sequence[str] | None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", type=Path, default=Path("runs/ppo"), help="output folder")
    p.add_argument("--minutes", type=float, default=26.0, help="training time budget")
    p.add_argument("--steps", type=int, default=None, help="step budget (with or for --minutes)")
    p.add_argument("--n-envs", type=int, default=2)
    p.add_argument("--vec", choices=("subproc", "dummy"), default="dummy")
    p.add_argument("--n-steps", type=int, default=PPO_SETTINGS["n_steps"])
    p.add_argument("--batch-size", type=int, default=PPO_SETTINGS["batch_size"])
    p.add_argument("--gamma", type=float, default=PPO_SETTINGS["gamma"])
    p.add_argument("--ent-coef", type=float, default=PPO_SETTINGS["ent_coef"])
    p.add_argument("--train-seeds", type=int, nargs=2, default=(0, 200), metavar=("LO", "HI"))
    p.add_argument("--eval-seed0", type=int, default=1000)
    p.add_argument("--eval-tracks", type=int, default=20)
    p.add_argument(
        "--path-preview", type=int, default=ENV_SETTINGS["path_preview"],
        help="global path points ahead in the observation (0: none)",
    )  # fmt: skip
    p.add_argument("--seed", type=int, default=0, help="PPO's seed")
    p.add_argument(
        "--train-env", action="append", default=[], metavar="KEY=VALUE", type=env_setting,
        help="a gym.make keyword for the training envs only, the value YAML "
        "(e.g. stuck_time=3); the held-out evaluation keeps the env's own",
    )  # fmt: skip
    return p.parse_args(argv)


def env_setting(text: str) -> tuple[str, Any]:
    """``KEY=VALUE`` as (key, the value read as YAML), for ``--train-env``."""
    key, sep, value = text.partition("=")
    if not sep or not key.strip():
        raise argparse.ArgumentTypeError(f"--train-env {text!r}: expected KEY=VALUE")
    try:
        return key.strip(), parse_value(value)
    except FieldError as exc:
        raise argparse.ArgumentTypeError(f"--train-env {text!r}: {exc.reason}") from None


def main(argv: Sequence[str] | None = None) -> dict[str, Any]:
    args = parse_args(argv)
    seeds = (int(args.train_seeds[0]), int(args.train_seeds[1]))
    env_settings = {**ENV_SETTINGS, "path_preview": args.path_preview}
    train_only = {**TRAIN_ENV_SETTINGS, **dict(args.train_env)}
    train_settings = {**env_settings, **train_only}
    try:  # before anything is written
        EnvConfig.from_dict({**train_settings, "track": "random", "track_seeds": seeds})
    except (TypeError, ValueError) as exc:
        print(f"train_ppo: --train-env: {exc}", file=sys.stderr)
        raise SystemExit(2) from None
    args.out.mkdir(parents=True, exist_ok=True)
    torch.set_num_threads(1)
    factories = [make_env(seeds, rank, train_settings) for rank in range(args.n_envs)]
    venv: VecEnv = (
        SubprocVecEnv(factories, start_method="fork")
        if args.vec == "subproc"
        else DummyVecEnv(factories)
    )
    venv = VecNormalize(VecMonitor(venv), norm_obs=False, norm_reward=True, gamma=args.gamma)
    settings = {
        **PPO_SETTINGS,
        "n_steps": args.n_steps,
        "batch_size": args.batch_size,
        "gamma": args.gamma,
        "ent_coef": args.ent_coef,
    }
    model = PPO("MlpPolicy", venv, seed=args.seed, verbose=0, device="cpu", **settings)
    budget_s = None if args.minutes <= 0 else args.minutes * 60.0
    total = args.steps if args.steps is not None else 10**9
    recorder = CurveRecorder(budget_s)
    load_before = load_average()
    print(f"training: {args.n_envs} envs ({args.vec}), budget {args.minutes} min / {total} steps")
    t0 = time.perf_counter()
    model.learn(total_timesteps=total, callback=recorder)
    train_s = time.perf_counter() - t0
    load_after = load_average()
    steps = int(model.num_timesteps)
    venv.close()
    model.save(args.out / "policy.zip")
    with (args.out / "curve.csv").open("w", newline="", encoding="utf-8") as f:
        writer = csv.DictWriter(f, fieldnames=CURVE_FIELDS)
        writer.writeheader()
        writer.writerows(recorder.rows)
    print(f"trained {steps} steps in {train_s / 60:.1f} min ({steps / train_s:.0f} steps/s)")
    plot_curve(
        recorder.rows,
        args.out / "learning_curve.png",
        f"PPO on generated tracks: {steps} steps, {train_s / 60:.0f} min",
    )

    print(f"evaluating on {args.eval_tracks} held-out tracks ...")
    tracks = held_out_tracks(args.eval_seed0, args.eval_tracks, seeds)
    results = evaluate(model, tracks, env_settings)
    ratios = [r.ratio for r in results if r.ratio is not None]
    figures = {
        "laps_completed_share": sum(r.lap_completed for r in results) / len(results),
        "lap_time_ratio_mean": round(float(np.mean(ratios)), 3) if ratios else None,
        "lap_time_ratio_max": round(float(np.max(ratios)), 3) if ratios else None,
        "return_mean": round(float(np.mean([r.return_ for r in results])), 2),
        "progress_share_mean": round(
            float(np.mean([min(r.progress_m / r.length_m, 1.0) for r in results])), 3
        ),
    }
    summary: dict[str, Any] = {
        "evaluation": {
            **figures,
            "tracks": len(results),
            "seeds": [t.seed for t in tracks],
            "per_track": [r.to_json() for r in results],
        },
        "training": {
            "steps": steps,
            "minutes": round(train_s / 60, 2),
            "steps_per_s": round(steps / train_s, 1),
            "episodes": len(recorder.rows),
            "return_curve": rising(recorder.rows, "return"),
            "progress_curve": rising(recorder.rows, "progress_m"),
            "load_before": load_before,
            "load_after": load_after,
            "cpus": os.cpu_count(),
        },
        "settings": {
            "env": {**env_settings, "track": "random", "track_seeds": list(seeds)},
            "train_env": train_only,
            "ppo": settings,
            "n_envs": args.n_envs,
            "vec": args.vec,
            "vec_normalize": {"norm_obs": False, "norm_reward": True},
            "seed": args.seed,
            "minutes_budget": args.minutes,
            "steps_budget": args.steps,
            "versions": {
                "python": sys.version.split()[0],
                "torch": torch.__version__,
                "stable_baselines3": _version("stable_baselines3"),
            },
        },
    }
    (args.out / "results.json").write_text(json.dumps(summary, indent=2) + "\n", encoding="utf-8")
    print(json.dumps(figures, indent=2))
    return summary


def _version(name: str) -> str:
    return version(name.replace("_", "-"))


if __name__ == "__main__":
    main()
