"""The one-way import rules of ARCHITECTURE.md, checked on the source tree."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("tracks", "sim", "localization", "planner", "envs")
# Dependency-free leaf modules of localization that the lower layers share, as
# every ROS node shares geometry_msgs and sensor_msgs.
LOCALIZATION_LEAVES = {"localization.pose", "localization.geodesy", "localization.messages"}

# package -> project packages it may import (beyond the leaves above).
ALLOWED: dict[str, set[str]] = {
    "tracks": set(),
    "sim": {"tracks"},
    "localization": {"tracks", "sim"},
    "planner": {"tracks", "localization"},
    "envs": {"tracks", "sim", "localization", "planner"},
}


def imports_of(path: Path) -> set[str]:
    """Absolute module names imported by one source file."""
    tree = ast.parse(path.read_text(), filename=str(path))
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
    return names


def sources(package: str) -> list[Path]:
    """Every Python file of a package."""
    return sorted((ROOT / package).rglob("*.py"))


@pytest.mark.parametrize("package", PACKAGES)
def test_imports_flow_one_way(package: str) -> None:
    """Each package imports only the layers below it (planner never imports sim)."""
    bad = []
    for path in sources(package):
        for name in imports_of(path):
            top = name.split(".")[0]
            if top not in PACKAGES or top == package:
                continue
            if any(name == leaf or name.startswith(leaf + ".") for leaf in LOCALIZATION_LEAVES):
                continue
            if top not in ALLOWED[package]:
                bad.append(f"{path.relative_to(ROOT)} imports {name}")
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize("package", [p for p in PACKAGES if p != "sim"])
def test_only_sim_imports_pymunk(package: str) -> None:
    """pymunk stays behind sim's own types."""
    bad = [
        str(path.relative_to(ROOT))
        for path in sources(package)
        if any(name.split(".")[0] == "pymunk" for name in imports_of(path))
    ]
    assert not bad


def test_leaves_are_dependency_free() -> None:
    """The shared localization leaves import no other project module but each other."""
    for leaf in LOCALIZATION_LEAVES:
        path = ROOT / (leaf.replace(".", "/") + ".py")
        if not path.exists():
            continue
        project = {n for n in imports_of(path) if n.split(".")[0] in PACKAGES}
        assert project <= LOCALIZATION_LEAVES, f"{leaf} imports {project - LOCALIZATION_LEAVES}"
