"""The shipped tracks are found after a plain (non-editable) ``pip install``.

Slow (a package build, ~2-5 s): the project's sources are copied to a
temporary directory (so the build writes nothing into the checkout),
installed with ``pip install --no-deps --target``, and a fresh interpreter
with only that target ahead of site-packages imports ``tracks`` from there and
loads every shipped track.
"""

from __future__ import annotations

import importlib.util
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PACKAGES = ("tracks", "localization", "sim", "planner", "envs")

CHECK = """
import sys
sys.path.insert(0, {target!r})
import tracks
assert tracks.__file__.startswith({target!r}), tracks.__file__
names = tracks.shipped_tracks()
assert names == {expected!r}, names
for name in names:
    track = tracks.load_track(name)
    assert str(track.source).startswith({target!r}), track.source
    assert track.global_path_file is not None and track.global_path_file.is_file()
    assert tracks.check_report(track)["errors"] == []
print("ok", len(names))
"""


def _copy_sources(dest: Path) -> Path:
    src = dest / "src"
    src.mkdir()
    for name in ("pyproject.toml", "README.md"):
        shutil.copy2(ROOT / name, src / name)
    for package in PACKAGES:
        if (ROOT / package).is_dir():
            shutil.copytree(
                ROOT / package, src / package, ignore=shutil.ignore_patterns("__pycache__", "*.pyc")
            )
    return src


def _pip_install(src: Path, target: Path) -> subprocess.CompletedProcess[str]:
    """Install without build isolation (offline, fast) if the venv has the build
    backend, else the ordinary way (pip fetches setuptools and wheel)."""
    base = [sys.executable, "-m", "pip", "install", "--no-deps", "--quiet", "--target", str(target)]
    done = subprocess.run(
        [*base, "--no-build-isolation", str(src)], capture_output=True, text=True, check=False
    )
    if done.returncode != 0:
        shutil.rmtree(target, ignore_errors=True)
        done = subprocess.run([*base, str(src)], capture_output=True, text=True, check=False)
    return done


@pytest.mark.slow
def test_shipped_tracks_found_after_pip_install(tmp_path: Path) -> None:
    """Non-editable install: tracks imports from the target and finds all shipped tracks."""
    if importlib.util.find_spec("pip") is None:
        pytest.skip("pip is not available in this interpreter")
    from tracks import shipped_tracks

    started = time.perf_counter()
    target = tmp_path / "target"
    done = _pip_install(_copy_sources(tmp_path), target)
    assert done.returncode == 0, done.stdout + done.stderr
    assert (target / "tracks" / "data" / "trackdrive.yaml").is_file()
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    run = subprocess.run(
        [sys.executable, "-c", CHECK.format(target=str(target), expected=shipped_tracks())],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    assert run.returncode == 0, run.stdout + run.stderr
    assert run.stdout.strip() == f"ok {len(shipped_tracks())}"
    print(f"pip install + load of the shipped tracks: {time.perf_counter() - started:.1f} s")
