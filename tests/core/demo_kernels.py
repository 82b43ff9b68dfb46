"""A small kernel package written into a temporary folder, and a fresh process to run it.

``ckdemo`` has the shapes that went stale under numba's own cache: a kernel
(``chain``) calling a kernel of another file (``step.step``), which calls a
helper of a third (``common.offset``), and reading a constant of a plain
module (``consts.SCALE``); plus a warm-up for :func:`parallel_warm_up`.
``chain(3.0)`` is ``(3 + OFFSET) * 3 * SCALE``.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from tests.child_process import python

PROBE = '''
from conesim.core.compiled import cached_njit


def _probe() -> None:
    """Nothing."""


_compiled = cached_njit(_probe, __name__)
'''

FILES = {
    "__init__.py": "",
    "consts.py": "SCALE = 2.0\n",
    "common.py": PROBE + "\n\n@_compiled\ndef offset(x):\n    return x + 1.0\n",
    "step.py": (
        "from ckdemo.common import offset\n"
        + PROBE
        + "\n\n@_compiled\ndef step(x):\n    return offset(x) * 3.0\n"
    ),
    "chain.py": (
        "from ckdemo import consts, step\n"
        + PROBE
        + "\n\n@_compiled\ndef chain(x):\n    return step.step(x) * consts.SCALE\n"
    ),
    "warm.py": (
        "from conesim.core.compiled import parallel_warm_up\n"
        "from ckdemo import chain, common\n\n\n"
        "@parallel_warm_up\n"
        "def warm_up():\n"
        "    chain.chain(3.0)\n"
        "    common.offset(1.0)\n"
    ),
}

RUN = """
import json, sys
sys.path.insert(0, {root!r})
from conesim.core import compiled
compiled._cores = compiled._idle_cores = lambda: {cores}  # as if it had that many
from ckdemo import chain, common, warm
{action}
stats = {{name: f.stats for name, f in (("chain", chain.chain), ("offset", common.offset))}}
print(json.dumps({{
    "value": chain.chain(3.0),
    "hits": {{k: sum(s.cache_hits.values()) for k, s in stats.items()}},
    "misses": {{k: sum(s.cache_misses.values()) for k, s in stats.items()}},
}}))
"""


def write_package(root: Path) -> Path:
    """Write ``ckdemo`` under ``root``; returns its folder."""
    package = root / "ckdemo"
    package.mkdir()
    for name, text in FILES.items():
        (package / name).write_text(text)
    return package


def edit(path: Path, old: str, new: str) -> None:
    """Replace ``old`` (present once) by ``new`` in ``path``."""
    text = path.read_text()
    assert text.count(old) == 1, (path, old)
    path.write_text(text.replace(old, new))


def run(root: Path, action: str = "", cores: int = 1, **env: str) -> tuple[dict[str, Any], str]:
    """In a fresh process: ``action``, then ``chain(3.0)``; (value, hits and misses of
    ``chain`` and ``offset`` in that process; its stderr)."""
    done = python(RUN.format(root=str(root), cores=cores, action=action), **env)
    return json.loads(done.stdout.strip().splitlines()[-1]), done.stderr


def cache_files(package: Path, pattern: str) -> list[Path]:
    """The cache files of ``package`` matching ``pattern`` (numba's in-tree ``__pycache__``)."""
    return sorted((package / "__pycache__").glob(pattern))
