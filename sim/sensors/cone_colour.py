"""Cone colour as a detector reports it: colour range, recognition, confusion.

A detection of true class c at true range r gets a label::

    if r <= colour_range and u1 < colour_probability:
        label ~ Categorical(confusion[c, :])        over COLOUR_CLASSES
    else:
        label = "unknown"

(fssim: colour only within 10 m, at 0.8 likelihood). ``confusion`` is
row-stochastic, rows = true class, columns = reported class, over
(blue, yellow, orange, unknown). A big orange cone uses the orange row; a big
cone labelled "orange" is reported as "big_orange" when ``report_big_orange``
(size is plain to a LiDAR or camera; only the hue can be confused), else as
"orange". A false positive has true class "unknown" and uses that row.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

COLOUR_CLASSES = ("blue", "yellow", "orange", "unknown")
UNKNOWN = 3  # index of "unknown" in COLOUR_CLASSES
ORANGE = 2
KIND_TO_CLASS = {"blue": 0, "yellow": 1, "orange": 2, "big_orange": 2, "unknown": 3}
IDENTITY_CONFUSION: tuple[tuple[float, ...], ...] = tuple(
    tuple(1.0 if i == j else 0.0 for j in range(4)) for i in range(4)
)
_ROW_SUM_TOL = 1e-9


def check_confusion(owner: str, field: str, matrix: tuple[tuple[float, ...], ...]) -> None:
    """Require a 4x4 row-stochastic matrix (entries in [0, 1], rows summing to 1)."""
    allowed = f"a 4x4 row-stochastic matrix over {COLOUR_CLASSES} (rows = true class)"
    m = np.asarray(matrix, dtype=float)
    if m.shape != (4, 4):
        raise ValueError(f"{owner}.{field} has shape {m.shape}: allowed {allowed}")
    if not np.all(np.isfinite(m)) or np.any(m < 0.0) or np.any(m > 1.0):
        raise ValueError(f"{owner}.{field} has entries outside [0, 1]: allowed {allowed}")
    sums = m.sum(axis=1)
    for i, s in enumerate(sums):
        if abs(s - 1.0) > _ROW_SUM_TOL:
            raise ValueError(
                f"{owner}.{field} row {i} (true {COLOUR_CLASSES[i]}) sums to {s:g}: "
                f"allowed {allowed}"
            )


def sample_colours(
    true_class: NDArray[np.intp],
    is_big: NDArray[np.bool_],
    coloured: NDArray[np.bool_],
    u: NDArray[np.float64],
    *,
    confusion_cdf: NDArray[np.float64],
    report_big_orange: bool,
) -> tuple[str, ...]:
    """Labels of n detections.

    Args:
        true_class: (n,) index into ``COLOUR_CLASSES`` of each true class.
        is_big: (n,) whether the cone is a big orange one.
        coloured: (n,) whether the colour was recognised (in colour range and
            the recognition draw succeeded).
        u: (n,) uniform draws in [0, 1) for the confusion step.
        confusion_cdf: (4, 4) row-wise cumulative sum of the confusion matrix.
        report_big_orange: report a big cone labelled orange as "big_orange".

    Returns:
        n labels from ``CONE_COLOURS``.
    """
    # Drawn from the cumulative row: the first class whose edge exceeds u.
    # Per detection on plain floats (a scan holds a few dozen at most, where
    # numpy's cost per call exceeds the work; the same comparisons).
    rows = confusion_cdf.tolist()
    labels = []
    for c, big, seen, draw in zip(
        true_class.tolist(), is_big.tolist(), coloured.tolist(), u.tolist(), strict=True
    ):
        k = UNKNOWN
        if seen:
            e0, e1, e2, e3 = rows[c]  # the four classes' cumulative edges
            k = min(int(draw >= e0) + (draw >= e1) + (draw >= e2) + (draw >= e3), UNKNOWN)
        big_label = report_big_orange and big and k == ORANGE
        labels.append("big_orange" if big_label else COLOUR_CLASSES[k])
    return tuple(labels)
