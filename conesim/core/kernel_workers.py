"""Helper processes that compile kernels into numba's cache while their parent waits.

Process plumbing only, for :mod:`conesim.core.compiled`: start ``count``
copies of a command with a fresh claims directory as its last argument, wait
for them, and stop any still running at the deadline or on an exception
(``KeyboardInterrupt``). A helper claims each unit of work by creating a file
there (:func:`claim`), so that the copies share the work without a
coordinator; the directory is removed afterwards.
"""

from __future__ import annotations

import contextlib
import hashlib
import logging
import os
import subprocess
import tempfile
import time
from collections.abc import Sequence
from typing import IO

_log = logging.getLogger(__name__)


def run(command: Sequence[str], count: int, timeout: float) -> bool:
    """Run ``count`` copies of ``command`` + [claims directory]; True if all ended with 0.

    Args:
        command: the program and its arguments.
        count: how many copies run at once.
        timeout: seconds for all of them; any still running then are killed.
    """
    with (
        tempfile.TemporaryDirectory(prefix="conesim-claims-") as claims,
        contextlib.ExitStack() as logs,
    ):
        procs: list[tuple[subprocess.Popen[bytes], IO[bytes]]] = []
        try:
            for _ in range(count):
                log = logs.enter_context(tempfile.TemporaryFile())
                out = subprocess.DEVNULL
                proc = subprocess.Popen([*command, claims], stdin=out, stdout=out, stderr=log)
                procs.append((proc, log))
            deadline = time.monotonic() + timeout
            return all([_ended_well(p, log, deadline) for p, log in procs])
        finally:
            for p, _ in procs:
                if p.poll() is None:
                    p.kill()
                    p.wait()


def _ended_well(proc: subprocess.Popen[bytes], log: IO[bytes], deadline: float) -> bool:
    """Wait for ``proc`` until ``deadline``; the tail of its stderr is logged if it failed."""
    try:
        code = proc.wait(timeout=max(0.0, deadline - time.monotonic()))
    except subprocess.TimeoutExpired:
        _log.debug("kernel helper %d ran past its deadline", proc.pid)
        return False
    if code != 0:
        log.seek(0)
        _log.debug("kernel helper %d ended with %d: %r", proc.pid, code, log.read()[-2000:])
    return code == 0


def claim(claims: str, key: str) -> bool:
    """True for the one caller (of all processes) that first claims ``key`` in ``claims``."""
    name = hashlib.sha256(key.encode()).hexdigest()[:32]
    try:
        os.close(os.open(os.path.join(claims, name), os.O_CREAT | os.O_EXCL | os.O_WRONLY))
    except FileExistsError:
        return False
    return True
