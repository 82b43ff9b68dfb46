"""The package as pip installs it: a wheel built from the sources, installed and used.

The wheel is built the way ``pip install conesim`` builds it (the
``[build-system]`` backend, setuptools), without build isolation so that no
network is needed: the backend comes with the ``dev`` extra. It must hold
every module of the packages under their ``conesim.*`` names (a wheel once
left out ``localization.ekf``, ``localization.frames`` and ``sim.sensors``,
which an editable install does not show), the shipped tracks and the
``py.typed`` markers, and nothing of the tests or of numba's caches.

Installed into a directory of its own, it is then used from a project that
has its own ``envs/`` and ``sim/`` packages, as many RL repositories do:
those must not shadow conesim (``gymnasium.make`` once failed there with
``NamespaceNotFound``).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
CACHES = shutil.ignore_patterns("__pycache__", "*.pyc", "*.nbi", "*.nbc")


def package_dirs() -> dict[str, str]:
    """pyproject's ``package-dir``: module name -> folder."""
    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    mapping: dict[str, str] = config["tool"]["setuptools"]["package-dir"]
    return mapping


@pytest.fixture(scope="module")
def wheel(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A wheel built from a copy of the sources."""
    src = tmp_path_factory.mktemp("src")
    for name in ("pyproject.toml", "README.md"):
        shutil.copy2(ROOT / name, src / name)
    for folder in package_dirs().values():
        shutil.copytree(ROOT / folder, src / folder, ignore=CACHES)
    dist = tmp_path_factory.mktemp("dist")
    command = [sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation"]
    build = subprocess.run(
        [*command, "-q", "-w", str(dist), str(src)],
        capture_output=True,
        text=True,
        check=False,
    )
    assert build.returncode == 0, build.stderr
    (built,) = dist.glob("conesim-*.whl")
    return built


@pytest.fixture(scope="module")
def wheel_files(wheel: Path) -> set[str]:
    """The file names in the wheel."""
    with zipfile.ZipFile(wheel) as archive:
        return set(archive.namelist())


def _sources(pattern: str) -> set[str]:
    """The package files matching ``pattern``, named as the wheel names them."""
    names: set[str] = set()
    for module, folder in package_dirs().items():
        base = module.replace(".", "/")
        for path in (ROOT / folder).rglob(pattern):
            if "__pycache__" in path.parts:
                continue
            rel = path.relative_to(ROOT / folder).as_posix()
            if module == "conesim" and rel.split("/")[0] in _mapped_children():
                continue
            names.add(f"{base}/{rel}")
    return names


def _mapped_children() -> set[str]:
    return {name.split(".")[1] for name in package_dirs() if "." in name}


def test_the_wheel_holds_every_module_track_file_and_type_marker(wheel_files: set[str]) -> None:
    """Every module under its ``conesim.*`` name, the tracks and the markers."""
    modules = _sources("*.py")
    nested = {
        "conesim/localization/ekf/filter.py",
        "conesim/sim/sensors/gps.py",
        "conesim/planner/kernels/track.py",
        "conesim/core/messages.py",
    }
    assert nested <= modules
    assert sorted(modules - wheel_files) == []
    tracks = {f"conesim/tracks/data/{p.name}" for p in (ROOT / "tracks" / "data").iterdir()}
    assert len(tracks) >= 8
    assert sorted(tracks - wheel_files) == []
    markers = _sources("py.typed")
    assert {f"{m.replace('.', '/')}/py.typed" for m in package_dirs()} <= markers
    assert sorted(markers - wheel_files) == []


def test_the_wheel_holds_no_tests_caches_or_top_level_packages(wheel_files: set[str]) -> None:
    """Only ``conesim/`` and the wheel's metadata: no bare ``envs``, no tests, no caches."""
    tops = {name.split("/")[0] for name in wheel_files}
    assert {t for t in tops if not t.endswith(".dist-info")} == {"conesim"}
    assert not [name for name in wheel_files if name.endswith((".nbi", ".nbc", ".pyc"))]
    assert any(name.endswith("entry_points.txt") for name in wheel_files)


USER_PROJECT = """
import sys

import envs  # the user's own packages, first on the path
import sim
assert envs.USER and sim.USER

import gymnasium as gym

env = gym.make("conesim:conesim/ConeTrack-v0", track="acceleration", sensors="ideal")
obs, info = env.reset(seed=0)
obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
assert env.observation_space.contains(obs)

import conesim.envs
import conesim.sim
from conesim.tracks import check_report, load_track, shipped_tracks

for module in (conesim.envs, conesim.sim):
    assert module.__file__.startswith(sys.argv[1]), module.__file__
names = shipped_tracks()
assert names == sorted(sys.argv[2].split(",")), names
for name in names:
    track = load_track(name)
    assert str(track.source).startswith(sys.argv[1]), track.source
    assert track.global_path_file is not None and track.global_path_file.is_file()
    assert check_report(track)["errors"] == []
print("ok")
"""


@pytest.mark.slow
def test_an_installed_conesim_is_not_shadowed_by_a_users_packages(
    wheel: Path, tmp_path: Path
) -> None:
    """From a project with its own ``envs/`` and ``sim/``: ``gym.make`` and the
    shipped tracks work, and conesim's modules come from the install."""
    from conesim.tracks import shipped_tracks

    target = tmp_path / "site"
    install = subprocess.run(
        [sys.executable, "-m", "pip", "install", "--no-deps", "-q", "--target", str(target),
         str(wheel)],
        capture_output=True, text=True, check=False,
    )  # fmt: skip
    assert install.returncode == 0, install.stderr
    project = tmp_path / "project"
    for name in ("envs", "sim"):
        (project / name).mkdir(parents=True)
        (project / name / "__init__.py").write_text("USER = True\n")
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    env["PYTHONPATH"] = str(target)
    run = subprocess.run(
        [sys.executable, "-c", USER_PROJECT, str(target), ",".join(shipped_tracks())],
        cwd=project,
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    assert run.returncode == 0, run.stdout + run.stderr
    assert run.stdout.strip().splitlines()[-1] == "ok"
