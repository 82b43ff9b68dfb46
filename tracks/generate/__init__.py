"""Random FS-rule tracks from a seed, and the loop builder they share with the shipped ones.

>>> from conesim.tracks.generate import TrackSpec, generate_track
>>> track = generate_track(7, TrackSpec(size="small"))  # the same cones for seed 7, always

``generator.py`` says what a generated track is and why it is our own;
``spec.py`` holds the settings and sizes; ``layout.py`` draws a layout,
``centreline.py`` closes it, ``loop.py`` and ``cones.py`` cone it.
"""

from __future__ import annotations

from conesim.tracks.generate.generator import generate_track
from conesim.tracks.generate.spec import GeneratedTrack, Size, TrackGenerationError, TrackSpec

__all__ = ["GeneratedTrack", "Size", "TrackGenerationError", "TrackSpec", "generate_track"]
