"""Track generation: loops from segments, their cones and gate (see generator.py)."""
