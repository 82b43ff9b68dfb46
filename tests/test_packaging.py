"""The package as pip installs it: a wheel built from the sources.

The wheel is built the way ``pip install conesim`` builds it (the
``[build-system]`` backend, setuptools), without build isolation so that no
network is needed: the backend comes with the ``dev`` extra. It must hold
every module of the five packages (their subpackages too: a wheel once left
out ``localization.ekf``, ``localization.frames`` and ``sim.sensors``, which
an editable install does not show), the shipped tracks and the ``py.typed``
markers, and nothing of the tests or of numba's caches.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("sim", "localization", "planner", "envs", "tracks")
CACHES = shutil.ignore_patterns("__pycache__", "*.pyc", "*.nbi", "*.nbc")


@pytest.fixture(scope="module")
def wheel_files(tmp_path_factory: pytest.TempPathFactory) -> set[str]:
    """The file names in a wheel built from a copy of the sources."""
    src = tmp_path_factory.mktemp("src")
    for name in ("pyproject.toml", "README.md"):
        shutil.copy2(ROOT / name, src / name)
    for package in PACKAGES:
        shutil.copytree(ROOT / package, src / package, ignore=CACHES)
    dist = tmp_path_factory.mktemp("dist")
    command = [sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation"]
    build = subprocess.run(
        [*command, "-q", "-w", str(dist), str(src)],
        capture_output=True,
        text=True,
        check=False,
    )
    assert build.returncode == 0, build.stderr
    (wheel,) = dist.glob("conesim-*.whl")
    with zipfile.ZipFile(wheel) as archive:
        return set(archive.namelist())


def _sources(pattern: str) -> set[str]:
    return {
        path.relative_to(ROOT).as_posix()
        for package in PACKAGES
        for path in (ROOT / package).rglob(pattern)
        if "__pycache__" not in path.parts
    }


def test_the_wheel_holds_every_module_track_file_and_type_marker(wheel_files: set[str]) -> None:
    modules = _sources("*.py")
    nested = {"localization/ekf/filter.py", "sim/sensors/gps.py", "planner/kernels/track.py"}
    assert nested <= modules
    assert sorted(modules - wheel_files) == []
    tracks = {f"tracks/data/{p.name}" for p in (ROOT / "tracks" / "data").iterdir()}
    assert len(tracks) >= 8
    assert sorted(tracks - wheel_files) == []
    markers = _sources("py.typed")
    assert {f"{package}/py.typed" for package in PACKAGES} <= markers
    assert sorted(markers - wheel_files) == []


def test_the_wheel_holds_no_tests_or_caches(wheel_files: set[str]) -> None:
    assert not [name for name in wheel_files if name.startswith(("tests/", "benchmarks/"))]
    assert not [name for name in wheel_files if name.endswith((".nbi", ".nbc", ".pyc"))]
    assert any(name.endswith("entry_points.txt") for name in wheel_files)
