"""The library logs; the application decides what is shown."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_library_warnings_stay_off_stderr_unless_configured() -> None:
    """Without a handler of the application's, a warning of the EKF or the
    track reader does not reach stderr (Python's last-resort handler); with
    logging configured it does."""
    code = (
        "import logging, sys\n"
        "import localization, tracks\n"
        "if sys.argv[1] == 'configured':\n"
        "    logging.basicConfig(level=logging.WARNING)\n"
        "logging.getLogger('conesim.localization.ekf').warning('rejected gps message')\n"
        "logging.getLogger('conesim.tracks.readers').warning('dropped a repeated cone')\n"
    )
    quiet = _python(code, "library")
    assert quiet.returncode == 0 and quiet.stderr == ""
    shown = _python(code, "configured")
    assert "rejected gps message" in shown.stderr and "dropped a repeated cone" in shown.stderr


def _python(code: str, arg: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-c", code, arg], check=False, cwd=ROOT, capture_output=True, text=True
    )
