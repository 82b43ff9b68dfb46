"""A cold warm-up's kernels compiled by the process and helper processes together.

For :func:`conesim.core.compiled.parallel_warm_up`; :func:`compile_in_parallel`:

1. Which kernels, for which types: every kernel in the packages' modules is
   swapped for a :class:`_Recorder`, the warm-up runs once as plain Python
   (milliseconds), and each call it makes to a kernel from Python (not from
   another kernel) is recorded with its numba argument types, as the
   dispatcher would type them; then the kernels are put back.
2. The calls, largest reach first (:func:`conesim.core.kernel_digest.code_size`),
   are written to a temporary directory, and helper processes start on them
   (:func:`run_helper`: import the modules, compile). This process compiles
   from the same list meanwhile: each call goes to whoever creates its claim
   file first, so no kernel is compiled twice and no process waits for a
   share it cannot start. Compiled code reaches the others through numba's
   cache; at the end this process waits for the helpers.

Anything that fails here (an interpreted run a kernel does not survive, a
helper that cannot start) costs only time: the warm-up, run again
afterwards, compiles what the cache still lacks and raises what it raises.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import importlib
import json
import logging
import os
import pickle
import subprocess
import sys
import tempfile
import time
import traceback
import types
from collections.abc import Callable, Iterator, Sequence, Set
from typing import IO, Any

from numba import typeof
from numba.extending import is_jitted

from conesim.core import kernel_digest

_log = logging.getLogger(__name__)

CALLS_NAME = "calls.pickle"
"""The list of calls in the claims directory: (module, name, numba argument types)."""

_HELPER_CODE = (
    "import json, sys; sys.path[:] = json.loads(sys.argv[1]); "
    "from conesim.core.kernel_workers import run_helper; sys.exit(run_helper(sys.argv[2:]))"
)

Call = tuple[Any, tuple[Any, ...]]
"""A kernel (dispatcher) and the argument types it is called with."""


class _Recording:
    """The calls recorded while a warm-up runs as Python, in order, once each."""

    active: _Recording | None = None

    def __init__(self) -> None:
        self.calls: dict[Call, None] = {}
        self.depth = 0


def discovering() -> bool:
    """True while a warm-up runs as Python to record its calls (a compile then is not its own)."""
    return _Recording.active is not None


def compile_in_parallel(
    run: Callable[[], object],
    kernels: Set[Any],
    packages: Set[str],
    helpers: int,
    timeout: float,
) -> None:
    """Compile into numba's cache every kernel call ``run`` makes, with ``helpers`` helpers.

    Args:
        run: the warm-up (it must be safe to run more than once).
        kernels: the dispatchers that may be swapped for recorders.
        packages: the top-level packages whose modules hold them.
        helpers: helper processes to start (0: this process alone).
        timeout: seconds the helpers get; any still running then are killed.
    """
    calls = discover(run, kernels, packages)
    calls.sort(key=lambda call: -kernel_digest.code_size(call[0].py_func, packages))
    if not calls:
        return
    with tempfile.TemporaryDirectory(prefix="conesim-kernels-") as claims:
        entries = [(d.py_func.__module__, d.py_func.__name__, sig) for d, sig in calls]
        with open(os.path.join(claims, CALLS_NAME), "wb") as f:
            pickle.dump(entries, f)
        command = [sys.executable, "-c", _HELPER_CODE, json.dumps(sys.path), claims]
        with _started(command if sys.executable else [], helpers) as wait:
            _compile_claimed(calls, claims)
            wait(timeout)


def discover(run: Callable[[], object], kernels: Set[Any], packages: Set[str]) -> list[Call]:
    """The kernel calls ``run`` makes from Python, found by running it as Python (see above);
    empty if it raises."""
    recorders: dict[int, _Recorder] = {}
    swapped: list[tuple[types.ModuleType, str, Any]] = []
    for module in list(sys.modules.values()):
        if (
            not isinstance(module, types.ModuleType)
            or module.__name__.split(".")[0] not in packages
        ):
            continue
        for name, value in list(vars(module).items()):
            if is_jitted(value) and value in kernels:
                recorder = recorders.setdefault(id(value), _Recorder(value))
                swapped.append((module, name, value))
                setattr(module, name, recorder)
    recording = _Recording.active = _Recording()
    try:
        run()
    except Exception:
        _log.debug("the warm-up failed as Python", exc_info=True)
        return []
    finally:
        _Recording.active = None
        for module, name, value in swapped:
            setattr(module, name, value)
    return list(recording.calls)


class _Recorder:
    """A kernel run as Python, recording the types it is called with from Python."""

    def __init__(self, dispatcher: Any) -> None:
        self.dispatcher = dispatcher
        functools.update_wrapper(self, dispatcher.py_func)

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        recording = _Recording.active
        if recording is None:
            return self.dispatcher.py_func(*args, **kwargs)
        if recording.depth == 0 and not kwargs:
            # ValueError: a type numba does not know (the warm-up will say so)
            with contextlib.suppress(ValueError):
                sig = tuple(typeof(a) for a in args)
                recording.calls.setdefault((self.dispatcher, sig), None)
        recording.depth += 1
        try:
            return self.dispatcher.py_func(*args, **kwargs)
        finally:
            recording.depth -= 1


def run_helper(argv: Sequence[str]) -> int:
    """A helper process: compile the calls listed in claims directory ``argv[0]`` not yet claimed.

    Returns:
        0, or 1 if something failed (the warm-up compiles what is missing).
    """
    (claims,) = argv
    with open(os.path.join(claims, CALLS_NAME), "rb") as f:
        entries = pickle.load(f)
    calls = [(getattr(importlib.import_module(m), name), sig) for m, name, sig in entries]
    return 0 if _compile_claimed(calls, claims, report=True) else 1


def _compile_claimed(calls: list[Call], claims: str, *, report: bool = False) -> bool:
    """Compile each call this process claims first; False if one failed (printed if ``report``)."""
    ok = True
    for dispatcher, sig in calls:
        if claim(claims, f"{dispatcher.py_func.__module__}.{dispatcher.py_func.__name__}{sig}"):
            try:
                dispatcher.compile(sig)
            except Exception:
                ok = False
                if report:
                    traceback.print_exc()
    return ok


def claim(claims: str, key: str) -> bool:
    """True for the one caller (of all processes) that first claims ``key`` in ``claims``."""
    name = hashlib.sha256(key.encode()).hexdigest()[:32]
    try:
        os.close(os.open(os.path.join(claims, name), os.O_CREAT | os.O_EXCL | os.O_WRONLY))
    except FileExistsError:
        return False
    return True


@contextlib.contextmanager
def _started(command: Sequence[str], count: int) -> Iterator[Callable[[float], bool]]:
    """Start ``count`` copies of ``command`` (none if it is empty); yields ``wait(timeout)``,
    True if all ended with 0. Any still running on leaving are killed."""
    with contextlib.ExitStack() as logs:
        procs: list[tuple[subprocess.Popen[bytes], IO[bytes]]] = []
        try:
            for _ in range(count if command else 0):
                log = logs.enter_context(tempfile.TemporaryFile())
                out = subprocess.DEVNULL
                procs.append((subprocess.Popen(command, stdin=out, stdout=out, stderr=log), log))

            def wait(timeout: float) -> bool:
                deadline = time.monotonic() + timeout
                return all([_ended_well(p, log, deadline) for p, log in procs])

            yield wait
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
