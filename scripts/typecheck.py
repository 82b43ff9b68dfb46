"""Type-check conesim under the names it is imported by (``conesim.sim``, ...), with mypy.

The packages' folders sit at the top of the repository (``sim/``,
``planner/``, ...), and setuptools installs them as ``conesim.sim``,
``conesim.planner``, ... (``[tool.setuptools.package-dir]`` in
pyproject.toml). mypy maps files to module names by folders only, so it
cannot read that mapping. This script builds the namespace as mypy needs to
see it, out of symbolic links under ``build/typecheck/`` (``conesim/sim ->
sim``, ...; rebuilt on every run from pyproject's mapping), runs mypy on its
files and on ``scripts/``, ``benchmarks/`` and ``examples/``, and prints mypy's report with the
real file names.

Usage: ``python scripts/typecheck.py [mypy options]`` (``make typecheck``).
Exit status: mypy's.
"""

from __future__ import annotations

import os
import shutil
import sys
import tomllib
from pathlib import Path

from mypy import api

ROOT = Path(__file__).resolve().parents[1]
VIEW = ROOT / "build" / "typecheck"
EXTRA = ("scripts", "benchmarks", "examples")  # checked as files, beside the package


def package_dirs() -> dict[str, str]:
    """pyproject's ``package-dir``: module name -> folder (relative to the root)."""
    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    mapping: dict[str, str] = config["tool"]["setuptools"]["package-dir"]
    return mapping


def build_view(mapping: dict[str, str]) -> dict[str, str]:
    """The linked namespace under ``VIEW``; returns view prefix -> real prefix."""
    shutil.rmtree(VIEW, ignore_errors=True)
    renames: dict[str, str] = {}
    top_name, top_dir = next((k, v) for k, v in mapping.items() if "." not in k)
    top = VIEW / top_name
    top.mkdir(parents=True)
    for entry in sorted((ROOT / top_dir).iterdir()):
        if entry.name != "__pycache__":
            os.symlink(entry, top / entry.name)
    for name, folder in mapping.items():
        if "." not in name:
            continue
        link = VIEW.joinpath(*name.split("."))
        os.symlink(ROOT / folder, link, target_is_directory=True)
        renames[link.relative_to(ROOT).as_posix() + "/"] = folder.rstrip("/") + "/"
    renames[top.relative_to(ROOT).as_posix() + "/"] = top_dir.rstrip("/") + "/"
    return renames


def view_sources() -> list[str]:
    """Every Python file of the view (through its links), caches left out."""
    found: list[str] = []
    for folder, subdirs, names in os.walk(VIEW, followlinks=True):
        subdirs[:] = sorted(d for d in subdirs if d != "__pycache__")
        found += [os.path.join(folder, n) for n in sorted(names) if n.endswith(".py")]
    return found


def main(argv: list[str]) -> int:
    """Build the view, run mypy, print its report with real paths."""
    os.chdir(ROOT)
    renames = build_view(package_dirs())
    os.environ["MYPYPATH"] = str(VIEW)
    files = [str(p) for folder in EXTRA for p in sorted((ROOT / folder).glob("*.py"))]
    out, err, status = api.run([*argv, *view_sources(), *files])
    # Longest prefix first: conesim/core/ lies inside conesim/.
    order = sorted(renames, key=len, reverse=True)
    for line in out.splitlines():
        view = next((v for v in order if line.startswith(v)), None)
        print(line if view is None else renames[view] + line[len(view) :])
    sys.stderr.write(err)
    return status


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
