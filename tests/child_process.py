"""A fresh Python process for the tests that need one (cold caches, clean imports)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]  # the child processes import from here


def python(script: str, **env: str) -> subprocess.CompletedProcess[str]:
    """Run ``script`` in a fresh Python from the repository, without the caller's ``NUMBA_*``
    settings but with ``env``; it must succeed."""
    done = subprocess.run(
        [sys.executable, "-c", script],
        capture_output=True,
        text=True,
        check=False,
        timeout=900,
        cwd=REPO,
        env={**{k: v for k, v in os.environ.items() if not k.startswith("NUMBA_")}, **env},
    )
    assert done.returncode == 0, done.stdout + done.stderr
    return done
