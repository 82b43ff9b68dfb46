"""pymunk bodies taken into a new space, for a new episode, as if built anew.

Building a world's ~200 pymunk bodies and shapes is most of the cost of a
reset (pymunk's attribute setters run Python code on every assignment), so
``World.reset`` keeps the car's and the cones' bodies and moves them into a
new space. A new space, not the old one emptied: Chipmunk keeps state in a
space that the bodies' next steps depend on, bit for bit (the step stamp,
the shape ids handed out in order and the spatial index built from them,
cached contacts, sleeping components). A body keeps only its own state: its
position, angle, velocities, force and torque, which the caller sets, and
the *bias* velocities of Chipmunk's contact solver (the push that separates
overlapping shapes, applied on the body's next position update), which
pymunk cannot read or set; :func:`spend_bias` clears them.
"""

from __future__ import annotations

from collections.abc import Sequence

import pymunk

_SPEND_STEP = 1.0  # [s] any step clears the bias; the positions it moves are set afterwards


def remove_from_space(bodies: Sequence[pymunk.Body]) -> None:
    """Take ``bodies`` and their shapes out of the space each is in (if any).

    Chipmunk wakes a sleeping body on its way out and drops its contacts: a
    body out of a space is awake, with no contacts and no idle time, as a new
    one is.
    """
    by_space: dict[pymunk.Space, list[pymunk.Body]] = {}
    for body in bodies:
        space = body.space
        if space is not None:
            by_space.setdefault(space, []).append(body)
    for space, members in by_space.items():
        space.remove(*(shape for body in members for shape in body.shapes))  # shapes first
        space.remove(*members)


def spend_bias(bodies: Sequence[pymunk.Body]) -> None:
    """Clear the contact solver's bias velocities of ``bodies``, which are in no space.

    Chipmunk spends a body's bias velocities on its next position update and
    zeroes them there; a step of a space holding these bodies alone (no
    shapes: no contacts, so no new bias) runs that update. It moves the
    bodies and changes their velocities: the caller sets those afterwards.
    """
    if not bodies:
        return
    scratch = pymunk.Space()
    scratch.add(*bodies)
    scratch.step(_SPEND_STEP)
    scratch.remove(*bodies)
