"""``slam`` localization through the command line, the scenario file and the env."""

from __future__ import annotations

import json
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

from conesim.envs.cli import main
from conesim.envs.runner import run_scenario
from conesim.envs.scenario import Scenario
from conesim.envs.scenario_file import load_scenario, scenario_to_mapping
from conesim.localization.slam import SlamConfig
from conesim.sim.sensors import get_profile
from conesim.tracks import load_track
from tests.localization.cone_helpers import assert_closed_loop_nis


def test_scenario_file_takes_slam_and_its_group(tmp_path: Path) -> None:
    """``localization: slam`` and a ``slam:`` group load; ``show`` writes the group back."""
    path = tmp_path / "s.yaml"
    path.write_text("conesim_scenario: 1\nlocalization: slam\nslam: {confirm_scans: 4}\n")
    scenario = load_scenario(path)
    assert scenario.localization == "slam"
    assert scenario.slam == SlamConfig(confirm_scans=4)
    assert scenario_to_mapping(scenario)["slam"]["confirm_scans"] == 4


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("slam: {confirm: 2}\n", "s.yaml:2: slam.confirm: unknown key 'confirm'; allowed keys: "),
        ("slam: {loop_radius: -1}\n", "s.yaml:2: slam.loop_radius: SlamConfig.loop_radius = "),
    ],
)
def test_bad_slam_settings_are_one_line_and_exit_2(
    text: str, message: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """An unknown or out-of-range slam setting: one located line, exit 2, nothing run."""
    path = tmp_path / "s.yaml"
    path.write_text("localization: slam\n" + text)
    code = main(["run", str(path), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith(f"conesim: error: {tmp_path / message}") or message in err, err
    assert len(err.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


def test_save_map_needs_slam(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``--save-map`` with ``fused``: one line, exit 2, before the run."""
    code = main(["run", "--save-map", str(tmp_path / "m.yaml"), "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert code == 2
    assert "--save-map needs --localization slam" in err
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize(
    ("track", "target", "message"),
    [
        ("skidpad", "m.yaml", "--save-map: a skidpad's map after its first lap holds one"),
        ("autocross", "afile/m.yaml", "afile is not a directory"),
        ("autocross", "m.csv", "a conesim track file ends in .yaml"),
    ],
)
def test_save_map_refusals_come_before_the_run(
    track: str, target: str, message: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A skidpad (its first lap maps one circle), a file as the map's folder, a
    suffix no track file has: one line, exit 2, nothing run or written."""
    (tmp_path / "afile").write_text("")
    args = ["run", "--track", track, "--localization", "slam", "--out", str(tmp_path / "o")]
    code = main([*args, "--save-map", str(tmp_path / target)])
    err = capsys.readouterr().err
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "o").exists() and not (tmp_path / target).exists()


def test_one_slam_lap_reports_its_map_and_saves_a_loadable_track(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """trackdrive, one lap, consumer GPS: a clean lap; the map after it has every cone
    within 0.5 m, none spurious; the saved map loads as a track with as many cones."""
    path = tmp_path / "map.yaml"
    args = ["run", "--track", "trackdrive", "--sensors", "consumer", "--localization", "slam"]
    code = main([*args, "--out", str(tmp_path / "o"), "--save-map", str(path), "--json"])
    result = json.loads(capsys.readouterr().out)
    assert code == 0 and result["clean"]
    q = result["map_quality"]
    assert result["map_quality_lap"] == 1
    assert q["missed"] <= 2 and q["spurious"] == 0 and q["max_error_m"] < 0.5
    assert result["landmarks"]["confirmed"] == q["landmarks"]
    assert result["cone_associations"]["scans"] > 100
    track = load_track(path)
    assert len(track.cones) == q["landmarks"]


def test_same_seed_same_slam_run() -> None:
    """Two 8 s slam runs with one seed: the same result.json apart from the timing."""

    def run() -> dict[str, object]:
        scenario = Scenario(
            track="autocross", seed=3, sensors=get_profile("consumer"), localization="slam",
            time_limit=8.0,
        )  # fmt: skip
        out = run_scenario(scenario).to_json()
        for key in ("wall_time_s", "real_time_factor", "setup_time_s"):
            out.pop(key)
        return out

    assert run() == run()


def test_env_takes_slam() -> None:
    """``gym.make(..., localization="slam", slam={...})``: the filter builds a map."""
    env = gym.make(
        "conesim:conesim/ConeTrack-v0", track="trackdrive", localization="slam",
        slam={"confirm_scans": 2},
    )  # fmt: skip
    env.reset(seed=0)
    for _ in range(100):
        env.step(np.array([0.0, 0.5], dtype=np.float32))
    ekf = env.unwrapped.loop.localizer.ekf  # type: ignore[attr-defined]
    counts = ekf.health.landmarks
    assert counts is not None and counts.confirmed > 5
    env.close()


@pytest.mark.slow
@pytest.mark.parametrize("track", ["autocross", "trackdrive"])
def test_closed_loop_slam_nis_near_one(track: str) -> None:
    """consumer GPS building the map, 2 laps: the cone updates' NIS per dof within
    10 % of 1 and >= 85 % of the scans inside their 95 % band (as with a given
    map, ``tests/localization/test_cones_monte_carlo.py``); every cone mapped,
    none spurious, and the map's shape right to 5 cm per cone once the common
    rotation and shift are taken out (measured 0.018 and 0.020 m)."""
    r = run_scenario(track, sensors="consumer", localization="slam", laps=2)
    assert_closed_loop_nis(r.cone_associations)
    assert r.clean
    quality = r.map_quality
    assert quality is not None
    assert quality["missed"] == 0 and quality["spurious"] == 0
    assert quality["mean_error_aligned_m"] <= 0.05
