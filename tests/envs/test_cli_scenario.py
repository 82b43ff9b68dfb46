"""Tests for `conesim run SCENARIO.yaml`, --set, `conesim scenario show`, and the
command line's one-line errors."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from conesim.envs import runner
from conesim.envs.cli import main
from conesim.envs.runner import TIMING_FIELDS, run_scenario
from conesim.envs.scenario_file import load_scenario
from conesim.sim.sensors import ConeFaults, Faults

SHORT = """\
track: acceleration
seed: 2
time_limit: 3.0
sensors:
  profile: rtk
  cones: {max_range: 18.0}
faults:
  cones: {detection_probability: 0.8, false_positives_per_scan: 0.5}
  gps:
    dropouts:
    - [1.0, 1.5]
"""


def cli(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    code = main(args)
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def result_of(directory: Path) -> dict[str, Any]:
    data = json.loads((directory / "result.json").read_text())
    return {k: v for k, v in data.items() if k not in TIMING_FIELDS}


def test_shown_scenario_saved_and_run_gives_the_same_result(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """run FILE; show FILE > shown.yaml; run shown.yaml: the same result.json apart
    from the timing fields, the embedded scenario included."""
    scenario = tmp_path / "short.yaml"
    scenario.write_text(SHORT)
    code, _, err = cli(["run", str(scenario), "--out", str(tmp_path / "a"), "--json"], capsys)
    assert code == 1, err  # the 3 s limit ends it: time_limit
    code, shown, _ = cli(["scenario", "show", str(scenario)], capsys)
    assert code == 0 and shown.startswith("# conesim scenario")
    (tmp_path / "shown.yaml").write_text(shown)
    code, _, err = cli(["run", str(tmp_path / "shown.yaml"), "--out", str(tmp_path / "b")], capsys)
    assert code == 1, err
    first, again = result_of(tmp_path / "a"), result_of(tmp_path / "b")
    assert first == again
    assert first["end_reason"] == "time_limit" and first["seed"] == 2
    embedded = first["scenario"]
    assert embedded["faults"]["cones"]["detection_probability"] == 0.8
    assert embedded["ekf"]["tuning"] == "rtk" and embedded["sensors"]["cones"]["max_range"] == 18.0


def test_a_scenario_in_code_and_from_its_show_yaml_run_the_same(tmp_path: Path) -> None:
    """run_scenario(Scenario) and run_scenario(load of its show YAML): bit for bit,
    and the old keywords give the same run as the scenario they describe."""
    from conesim.envs.scenario import Scenario
    from conesim.envs.scenario_file import scenario_yaml

    in_code = Scenario(track="acceleration", seed=4, time_limit=2.0,
                       faults=Faults(cones=ConeFaults(noise_scale=2.0)))  # fmt: skip
    (tmp_path / "s.yaml").write_text(scenario_yaml(in_code))
    a = run_scenario(in_code).to_json()
    b = run_scenario(load_scenario(tmp_path / "s.yaml")).to_json()
    c = run_scenario("acceleration", seed=4, time_limit=2.0,
                     faults=Faults(cones=ConeFaults(noise_scale=2.0))).to_json()  # fmt: skip
    for result in (a, b, c):
        for key in TIMING_FIELDS:
            result.pop(key)
    assert a == b == c


def test_set_and_flags_override_the_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """The file, then each --set, then the flags: --seed wins over --set seed."""
    seen: list[Any] = []
    monkeypatch.setattr(
        runner, "run_scenario", lambda scenario, **_: seen.append(scenario) or 1 / 0
    )
    path = tmp_path / "s.yaml"
    path.write_text(SHORT)
    with pytest.raises(ZeroDivisionError):
        main(["run", str(path), "--set", "seed=5", "--set", "sensors.cones.max_range=25",
              "--set", "faults.cones.detection_probability=0.7", "--seed", "9",
              "--sensors", "consumer", "--out", str(tmp_path / "o")])  # fmt: skip
    (scenario,) = seen
    assert scenario.seed == 9 and scenario.sensors.name == "consumer"
    assert scenario.sensors.cones.max_range == 25.0
    assert scenario.faults.cones.detection_probability == 0.7
    assert scenario.time_limit == 3.0 and scenario.track == "acceleration"


def test_scenario_show_without_a_file_shows_what_the_flags_run(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """`scenario show --track autocross --sensors consumer` is the YAML of that run."""
    code, out, _ = cli(["scenario", "show", "--track", "autocross", "--sensors", "consumer",
                        "--set", "ekf.gate_probability=0.99"], capsys)  # fmt: skip
    assert code == 0
    assert "\ntrack: autocross\n" in out and "  profile: consumer\n" in out
    assert "  tuning: consumer\n" in out and "  gate_probability: 0.99\n" in out


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["run", "--seed", "abc"], "argument --seed: invalid int value: 'abc' (see 'conesim run"),
        (["run", "--laps", "1.5"], "argument --laps: invalid int value: '1.5'"),
        (["run", "--sensors", "gnss"], "argument --sensors: invalid choice: 'gnss'"),
        (["run", "--speed"], "unrecognized arguments: --speed (see 'conesim --help')"),
        (["scenario"], "the following arguments are required: ACTION"),
        ([], "the following arguments are required: COMMAND (see 'conesim --help')"),
        (["run", "--set", "laps"], "--set laps: expected KEY=VALUE, e.g. --set laps=2"),
        (["run", "--set", "laps=[1"], "--set laps=[1: not valid YAML:"),
        (["run", "--set", "sensors.cones.range=20"],
         "--set sensors.cones.range=20: sensors.cones.range: unknown key 'range'; allowed keys:"),
        (["run", "--set", "laps=0"], "--set laps=0: laps: Scenario.laps = 0 is out of range"),
        (["run", "missing.yaml"], "missing.yaml: no such file"),
        (["run", "--out", "/"], "--out /: is the root directory"),
        (["scenario", "show", "--track", "monza"],
         "--track monza: 'monza' is neither a shipped track"),
        (["run", "--set", "track=../x.yaml"],
         "--set track=../x.yaml: '../x.yaml' is neither a shipped track"),
    ],
)  # fmt: skip
def test_every_command_line_error_is_one_line_exit_2(
    args: list[str], message: str, capsys: pytest.CaptureFixture[str], tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:  # fmt: skip
    """argparse's errors too: one line, exit 2, nothing on stdout, nothing written."""
    monkeypatch.chdir(tmp_path)
    code, out, err = cli(args, capsys)
    assert code == 2 and out == ""
    assert len(err.splitlines()) == 1, err
    assert err.startswith("conesim: error: ") and message in err, err
    assert list(tmp_path.iterdir()) == []


def test_a_missing_track_in_a_scenario_file_names_the_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``track: nosuch.yaml`` in a scenario: the error names the file and where a
    relative track is looked for."""
    (tmp_path / "s.yaml").write_text("track: nosuch.yaml\n")
    code, _, err = cli(["run", str(tmp_path / "s.yaml"), "--out", str(tmp_path / "o")], capsys)
    assert code == 2 and not (tmp_path / "o").exists()
    assert err.startswith(f"conesim: error: {tmp_path / 's.yaml'}: track (a file is looked for "
                          "beside the scenario file): 'nosuch.yaml' is neither"), err  # fmt: skip


def test_a_bad_scenario_file_writes_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A range error in the file: its line, exit 2, no output directory."""
    path = tmp_path / "s.yaml"
    path.write_text("track: acceleration\nfaults:\n  cones:\n    detection_probability: 2\n")
    code, out, err = cli(["run", str(path), "--out", str(tmp_path / "o")], capsys)
    assert code == 2 and out == "" and not (tmp_path / "o").exists()
    assert err == (
        f"conesim: error: {path}:4: faults.cones.detection_probability: "
        "ConeFaults.detection_probability = 2.0 is out of range: allowed [0, 1]\n"
    )


def test_out_may_be_a_previous_run_or_the_scenarios_folder(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A run folder holding its scenario: the first run writes beside it, the second
    replaces the outputs; a folder of other files is refused."""
    folder = tmp_path / "run"
    folder.mkdir()
    (folder / "s.yaml").write_text("track: acceleration\ntime_limit: 0.5\n")
    for _ in range(2):
        code, _, err = cli(["run", str(folder / "s.yaml"), "--out", str(folder)], capsys)
        assert code == 1, err
    assert sorted(p.name for p in folder.iterdir()) == ["result.json", "run.png", "s.yaml"]
    (tmp_path / "src").mkdir()
    (tmp_path / "src" / "main.py").write_text("")
    code, _, err = cli(["run", str(folder / "s.yaml"), "--out", str(tmp_path / "src")], capsys)
    assert code == 2 and "holds other files (main.py)" in err
    assert [p.name for p in (tmp_path / "src").iterdir()] == ["main.py"]
