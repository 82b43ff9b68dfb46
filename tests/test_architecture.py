"""The one-way import rules of docs/ARCHITECTURE.md, checked on the source tree.

Every module of conesim imports the others as ``conesim.<package>``; the
packages form layers, each importing only those below it::

    core  <-  tracks  <-  sim  <-  localization  <-  planner  <-  envs

with two cuts through the stack: ``localization`` and ``planner`` never
import ``sim`` (the car's software sees messages, the frame tree and the
global path, never the simulator's truth), and nothing but ``sim`` imports
pymunk. ``core`` is the shared vocabulary and imports no other package.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

FOLDERS = {
    "core": ROOT / "conesim" / "core",
    "tracks": ROOT / "tracks",
    "sim": ROOT / "sim",
    "localization": ROOT / "localization",
    "planner": ROOT / "planner",
    "envs": ROOT / "envs",
}
"""Each package of the ``conesim`` namespace and the folder it lives in."""

ALLOWED: dict[str, set[str]] = {
    "core": set(),
    "tracks": {"core"},
    "sim": {"core", "tracks"},
    "localization": {"core", "tracks"},
    "planner": {"core", "tracks", "localization"},
    "envs": {"core", "tracks", "sim", "localization", "planner"},
}
"""package -> the other packages it may import."""

OLD_NAMES = ("sim", "localization", "planner", "envs", "tracks")


def imports_of(path: Path) -> set[str]:
    """Absolute module names imported by one source file (relative ones resolved
    against ``conesim``'s namespace are not used: the tree has none)."""
    tree = ast.parse(path.read_text(), filename=str(path))
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
            if node.module == "conesim":  # from conesim import envs
                names.update(f"conesim.{alias.name}" for alias in node.names)
    return names


def sources(package: str) -> list[Path]:
    """Every Python file of a package."""
    return sorted(FOLDERS[package].rglob("*.py"))


def package_of(name: str) -> str | None:
    """The conesim package a module name belongs to (``conesim.sim.world`` -> ``sim``)."""
    parts = name.split(".")
    if parts[0] != "conesim" or len(parts) < 2:
        return None
    return parts[1] if parts[1] in FOLDERS else None


@pytest.mark.parametrize("package", list(FOLDERS))
def test_imports_flow_one_way(package: str) -> None:
    """Each package imports only the layers below it (planner never imports sim)."""
    bad = []
    for path in sources(package):
        for name in imports_of(path):
            other = package_of(name)
            if other is not None and other != package and other not in ALLOWED[package]:
                bad.append(f"{path.relative_to(ROOT)} imports {name}")
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize("package", list(FOLDERS))
def test_imports_use_the_one_namespace(package: str) -> None:
    """No module imports a package by its folder's bare name (``import envs``),
    which a user's own ``envs/`` folder would shadow."""
    bad = [
        f"{path.relative_to(ROOT)} imports {name}"
        for path in sources(package)
        for name in imports_of(path)
        if name.split(".")[0] in OLD_NAMES
    ]
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize("package", [p for p in FOLDERS if p != "sim"])
def test_only_sim_imports_pymunk(package: str) -> None:
    """pymunk stays behind sim's own types."""
    bad = [
        str(path.relative_to(ROOT))
        for path in sources(package)
        if any(name.split(".")[0] == "pymunk" for name in imports_of(path))
    ]
    assert not bad


def test_the_top_package_imports_no_layer() -> None:
    """``import conesim`` registers the env and loads no package of the stack."""
    names = imports_of(ROOT / "conesim" / "__init__.py")
    assert not {n for n in names if package_of(n) is not None}


def test_the_rules_cover_every_package() -> None:
    """Every folder of a package is in the rules, and the rules name no other."""
    assert set(ALLOWED) == set(FOLDERS)
    for package, folder in FOLDERS.items():
        assert (folder / "__init__.py").is_file(), package


NUMBA_INTERNALS = {"conesim/core/kernel_cache.py"}
"""The one module that reaches into numba's private attributes, on purpose: it
keys numba's cache by the code a kernel reaches; numba is pinned, and
tests/core/test_kernel_cache.py checks every internal it relies on."""


def test_no_module_reads_another_objects_private_state() -> None:
    """``x._name`` only on ``self`` or ``cls``: adapters read what objects return
    or expose, never another object's private attributes."""
    bad = []
    for package in FOLDERS:
        for path in sources(package):
            if path.relative_to(ROOT).as_posix() in NUMBA_INTERNALS:
                continue
            tree = ast.parse(path.read_text(), filename=str(path))
            for node in ast.walk(tree):
                private = (
                    isinstance(node, ast.Attribute)
                    and node.attr.startswith("_")
                    and not node.attr.startswith("__")
                )
                if private and not (
                    isinstance(node.value, ast.Name) and node.value.id in ("self", "cls")
                ):
                    bad.append(f"{path.relative_to(ROOT)}:{node.lineno}: {ast.unparse(node)}")
    assert not bad, "\n".join(bad)
