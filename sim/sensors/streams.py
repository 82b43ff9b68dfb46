"""Random streams: one generator per sensor and noise source, from the episode seed.

A sensor's generator is derived from the episode seed *and* stable integer keys
of its name (and of a sub-stream name such as ``"white"`` or ``"multipath"``)::

    SeedSequence(seed, spawn_key=(crc32(sensor_name), crc32(source_name)))

so that changing one sensor's settings (or switching a fault on) never shifts
another stream's draws. ``zlib.crc32`` is stable across runs and platforms;
Python's ``hash()`` of a string is salted per process and is never used.
The global ``np.random`` state is never touched.
"""

from __future__ import annotations

import zlib

import numpy as np


def stable_key(name: str) -> int:
    """A process-independent 32-bit key of a name (CRC-32 of its UTF-8 bytes).

    >>> stable_key("gps")
    1424645575
    """
    return zlib.crc32(name.encode("utf-8"))


def stream(seed: int, *names: str) -> np.random.Generator:
    """The generator of one named stream of the episode ``seed``.

    Args:
        seed: episode seed, a non-negative integer.
        *names: path of names, e.g. ``("gps", "white")``.

    Returns:
        A fresh ``numpy.random.Generator`` (PCG64).

    Raises:
        ValueError: a negative or non-integer seed.
    """
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise ValueError(f"seed = {seed!r} is out of range: allowed a non-negative integer")
    keys = tuple(stable_key(n) for n in names)
    return np.random.default_rng(np.random.SeedSequence(int(seed), spawn_key=keys))
