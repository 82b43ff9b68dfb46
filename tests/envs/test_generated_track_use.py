"""Generated tracks reached three ways: ``conesim track generate``, a scenario's
``track: {generate: ...}``, and the gym env."""

from __future__ import annotations

import json
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

from conesim import envs
from conesim.envs.cli import main
from conesim.envs.scenario import Scenario
from conesim.envs.scenario_file import load_scenario, scenario_yaml
from conesim.tracks import GeneratedTrack, TrackSpec, generate_track, read_track

SEED = 2024  # the tests' own; the benchmarks use others


def run_cli(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    """Exit code, stdout and stderr of one invocation."""
    code = main(args)
    out = capsys.readouterr()
    return code, out.out, out.err


def test_generate_then_check_show_and_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`track generate` writes the generator's track; `track check` passes it, `track show`
    draws it and `run --track FILE` drives a clean lap of it."""
    file = tmp_path / "gen.yaml"
    code, out, err = run_cli(
        ["track", "generate", "--seed", str(SEED), "--size", "small", "--out", str(file)], capsys
    )
    assert code == 0 and err == "", err
    assert f"generated-small-{SEED}" in out
    assert read_track(file) == generate_track(SEED, TrackSpec(size="small"))
    code, out, _ = run_cli(["track", "check", str(file)], capsys)
    assert code == 0 and "ok: no warnings, no errors" in out
    code, out, _ = run_cli(["track", "show", str(file), "--out", str(tmp_path / "g.png")], capsys)
    assert code == 0 and (tmp_path / "g.png").read_bytes()[:4] == b"\x89PNG"
    run_dir = tmp_path / "run"
    args = ["run", "--track", str(file), "--sensors", "ideal", "--localization", "truth"]
    code, out, _ = run_cli([*args, "--out", str(run_dir), "--json"], capsys)
    result = json.loads(out)
    assert result["track"] == f"generated-small-{SEED}"
    assert result["laps_completed"] == 1, result["end_reason"]


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--seed", "1", "--width", "2", "3"], "--width: TrackSpec.width = (2, 3) is out of range"),
        (["--seed", "-1"], "--seed -1: must be a non-negative integer"),
        (["--seed", "x"], "argument --seed: invalid int value: 'x'"),
        (["--seed", "1", "--size", "huge"], "argument --size: invalid choice: 'huge'"),
        (["--seed", "1", "--length", "60", "61"], "seed 1: no track in 200 attempts"),
        (["--seed", "1", "--tight-share", "2"], "--tight-share: TrackSpec.tight_share = 2.0"),
    ],
)
def test_generate_bad_input_is_one_line_exit_2(
    args: list[str], message: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Bad settings, a bad seed, or a seed and spec that make no track: one line, exit 2,
    nothing written."""
    file = tmp_path / "gen.yaml"
    code, _, err = run_cli(["track", "generate", *args, "--out", str(file)], capsys)
    assert code == 2
    assert len(err.strip().splitlines()) == 1 and message in err, err
    assert not file.exists()


def test_generate_wants_a_yaml_name(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``--out g.csv``: the conesim format is YAML, so the name is refused (exit 2)."""
    file = tmp_path / "g.csv"
    code, _, err = run_cli(["track", "generate", "--seed", "1", "--out", str(file)], capsys)
    assert code == 2 and "a conesim track file ends in .yaml" in err and not file.exists()


def test_scenario_file_generates_its_track(tmp_path: Path) -> None:
    """`track: {generate: {seed, size, ...}}` in a scenario file is a GeneratedTrack;
    `scenario show` writes every setting out and reads back the same scenario."""
    path = tmp_path / "s.yaml"
    path.write_text(f"track: {{generate: {{seed: {SEED}, size: large, tight_share: 0.5}}}}\n")
    scenario = load_scenario(path)
    assert scenario.track == GeneratedTrack(SEED, TrackSpec(size="large", tight_share=0.5))
    shown = tmp_path / "shown.yaml"
    shown.write_text(scenario_yaml(scenario))
    assert "  generate:\n" in shown.read_text() and "max_attempts: 200" in shown.read_text()
    assert load_scenario(shown).track == scenario.track


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("track: {generate: {sed: 1}}", "s.yaml:1: track.generate.sed: unknown key 'sed'"),
        ("track: {make: {seed: 1}}", "track.make: unknown key 'make'; allowed keys: generate"),
        ("track: {generate: {seed: -2}}", "track.generate.seed: GeneratedTrack.seed = -2"),
        ("track: {generate: {seed: 1, size: 7}}", "track.generate.size: expected one of"),
        (
            "track: {generate: {seed: 1, width: [2, 3]}}",
            "track.generate.width: TrackSpec.width = (2, 3) is out of range",
        ),
        ("track: {generate: [1]}", "track.generate: expected a mapping of generator settings"),
    ],
)
def test_bad_generate_in_a_scenario_is_one_line_exit_2(
    text: str, message: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Unknown keys, ranges and types of the generator's settings: one located line, exit 2."""
    path = tmp_path / "s.yaml"
    path.write_text(text + "\n")
    code, _, err = run_cli(["scenario", "show", str(path)], capsys)
    assert code == 2
    assert len(err.strip().splitlines()) == 1 and message in err, err


def test_set_overrides_the_generated_seed(tmp_path: Path) -> None:
    """A dotted override changes one generator setting: a sweep over seeds."""
    path = tmp_path / "s.yaml"
    path.write_text("track: {generate: {seed: 1, size: small}}\n")
    scenario = load_scenario(path, {"track.generate.seed": 8})
    assert scenario.track == GeneratedTrack(8, TrackSpec(size="small"))


def test_env_runs_on_a_generated_track() -> None:
    """`gymnasium.make(..., scenario=...)` with a generated track, or `track=` a mapping,
    resets on that track and steps; the same seed gives the same observations."""
    recipe = GeneratedTrack(SEED, TrackSpec(size="small"))
    env = gym.make(envs.ENV_ID, scenario=Scenario(track=recipe), sensors="ideal")
    other = gym.make(envs.ENV_ID, track={"generate": {"seed": SEED, "size": "small"}})
    try:
        env.reset(seed=3)
        assert env.unwrapped.loop.track.name == f"generated-small-{SEED}"
        assert other.unwrapped.loop.track == env.unwrapped.loop.track
        for _ in range(20):
            _, _, terminated, truncated, _ = env.step(np.array([0.0, 0.5], np.float32))
            assert not (terminated or truncated)
        obs2, _ = env.reset(seed=3)
        assert np.array_equal(env.reset(seed=3)[0], obs2)
    finally:
        env.close()
        other.close()
