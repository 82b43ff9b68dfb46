"""Fuzzing every reader: random bytes and mutated valid files load or raise TrackFormatError.

A file that loads must also give finite geometry and a validator report
(findings, not exceptions). Hypothesis runs derandomized so that CI is
reproducible; raise FUZZ_EXAMPLES locally for a longer hunt.
"""

from __future__ import annotations

import math
import os
import re
import tempfile
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from conesim.tracks import TrackFormatError, check_report, read_track

FUZZ_EXAMPLES = int(os.environ.get("FUZZ_EXAMPLES", "120"))
FUZZ = settings(
    max_examples=FUZZ_EXAMPLES,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.too_slow],
)


def _ring(radius: float, count: int, phase: float = 0.0) -> list[tuple[float, float]]:
    return [
        (
            round(radius * math.cos(phase + 2 * math.pi * k / count), 3),
            round(radius * math.sin(phase + 2 * math.pi * k / count), 3),
        )
        for k in range(count)
    ]


BLUE, YELLOW = _ring(8.0, 14), _ring(12.0, 20, 0.1)  # a small counter-clockwise loop
BIG = [(8.0, -0.4), (8.0, 0.4), (12.0, -0.4), (12.0, 0.4)]  # start line at (8..12, 0)


def _pairs(points: list[tuple[float, float]]) -> str:
    return "[" + ", ".join(f"[{x}, {y}]" for x, y in points) + "]"


CONESIM = (
    "conesim_track: 1\nname: fuzz\nlayout: closed\nstart_pose: [10.0, -2.0, 1.5708]\n"
    f"global_path: null\ncones:\n  blue: {_pairs(BLUE)}\n  yellow: {_pairs(YELLOW)}\n"
    f"  big_orange: {_pairs(BIG)}\n"
)
FSSIM = (
    "".join(
        f"{key}:\n" + "".join(f"- - {x}\n  - {y}\n" for x, y in pts)
        for key, pts in (("cones_left", BLUE), ("cones_right", YELLOW), ("cones_orange_big", BIG))
    )
    + "starting_pose_front_wing:\n- 10.0\n- -2.0\n- 1.5708\ntk_device:\n- - 0.0\n  - 2.4\n"
)
EUFS = (
    "tag,x,y,direction,x_variance,y_variance,xy_covariance\n"
    "car_start,10.0,-2.0,1.5708,0.0,0.0,0.0\n"
    + "".join(f"blue,{x},{y},0.0,0.01,0.01,0.0\n" for x, y in BLUE)
    + "".join(f"yellow,{x},{y},0.0,0.01,0.01,0.0\n" for x, y in YELLOW)
    + "".join(f"big_orange,{x},{y},0.0,0.01,0.01,0.0\n" for x, y in BIG)
    + "midpoint,10.0,0.0,0.0,0.0,0.0,0.0\n"
)
FSDS = (
    "".join(f"blue,{x},{y},0,0,0,0\n" for x, y in BLUE)
    + "".join(f"yellow,{x},{y},0,0,0,0\n" for x, y in YELLOW)
    + "".join(f"big_orange,{x},{y},0,0,0,0\n" for x, y in BIG)
)
TEMPLATES = {"conesim": CONESIM, "fssim": FSSIM, "eufs": EUFS, "fsds": FSDS}

PIECES = st.sampled_from(
    [
        "0",
        "1",
        "-",
        ".",
        "e",
        "9e9",
        ",",
        "\n",
        " ",
        "[",
        "]",
        ":",
        "- ",
        "nan",
        "inf",
        "null",
        "blue",
        "yellow",
        "big_orange",
        "car_start",
        "'",
        '"',
        "&a",
        "*a",
        "{",
        "}",
        "\t",
        "#",
        "\x00",
    ]
)


NUMBERS = st.one_of(
    st.floats(-30.0, 30.0, allow_nan=False),
    st.sampled_from([0.0, -0.0, 1e-12, 1e5, -2e6, 1e300, 5e-324]),
)
NUMBER = re.compile(r"-?\d+\.\d+")


@st.composite
def mutated(draw: st.DrawFn, template: str) -> str:
    """The template after 1-4 random edits: a number changed, characters deleted,
    inserted or replaced, a line duplicated, dropped or swapped, the file cut."""
    text = template
    for _ in range(draw(st.integers(1, 4))):
        ops = ["number", "number", "delete", "insert", "replace", "dup", "drop", "swap", "cut"]
        op = draw(st.sampled_from(ops))
        pos = draw(st.integers(0, max(len(text) - 1, 0)))
        lines = text.split("\n")
        i = draw(st.integers(0, len(lines) - 1))
        j = draw(st.integers(0, len(lines) - 1))
        numbers = list(NUMBER.finditer(text))
        if op == "number" and numbers:
            m = numbers[draw(st.integers(0, len(numbers) - 1))]
            text = text[: m.start()] + repr(draw(NUMBERS)) + text[m.end() :]
        elif op == "delete":
            text = text[:pos] + text[pos + draw(st.integers(1, 12)) :]
        elif op == "insert":
            text = text[:pos] + "".join(draw(st.lists(PIECES, min_size=1, max_size=4))) + text[pos:]
        elif op == "replace":
            text = text[:pos] + draw(PIECES) + text[pos + 1 :]
        elif op == "dup":
            lines.insert(i, lines[i])
            text = "\n".join(lines)
        elif op == "drop":
            del lines[i]
            text = "\n".join(lines)
        elif op == "swap":
            lines[i], lines[j] = lines[j], lines[i]
            text = "\n".join(lines)
        else:
            text = text[:pos]
    return text


def load_or_format_error(data: bytes, suffix: str) -> None:
    """read_track either returns a usable track or raises TrackFormatError; nothing else."""
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / f"fuzz{suffix}"
        path.write_bytes(data)
        try:
            track = read_track(path)
        except TrackFormatError as exc:
            assert str(exc).startswith(str(path))
            return
    assert np.all(np.isfinite(track.centreline)) and track.length_m > 0
    report = check_report(track)
    assert set(report) == {"cones", "length_m", "width_min_m", "width_max_m", "warnings", "errors"}


def test_templates_are_valid() -> None:
    """The unmutated templates load (else the mutation tests prove little)."""
    for name, text in TEMPLATES.items():
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / f"{name}.txt"
            path.write_text(text)
            assert check_report(read_track(path))["errors"] == [], name


@FUZZ
@given(st.binary(max_size=3000))
def test_random_bytes(data: bytes) -> None:
    """Random bytes."""
    load_or_format_error(data, ".csv")


@FUZZ
@given(st.text(max_size=2000))
def test_random_text(text: str) -> None:
    """Random unicode text."""
    load_or_format_error(text.encode("utf-8", "surrogatepass"), ".yaml")


@FUZZ
@given(mutated(CONESIM))
def test_mutated_conesim_yaml(text: str) -> None:
    """Mutated files of our own format."""
    load_or_format_error(text.encode("utf-8", "surrogatepass"), ".yaml")


@FUZZ
@given(mutated(FSSIM))
def test_mutated_fssim_yaml(text: str) -> None:
    """Mutated fssim files."""
    load_or_format_error(text.encode("utf-8", "surrogatepass"), ".yaml")


@FUZZ
@given(mutated(EUFS))
def test_mutated_eufs_csv(text: str) -> None:
    """Mutated EUFS files."""
    load_or_format_error(text.encode("utf-8", "surrogatepass"), ".csv")


@FUZZ
@given(mutated(FSDS))
def test_mutated_fsds_csv(text: str) -> None:
    """Mutated FSDS files."""
    load_or_format_error(text.encode("utf-8", "surrogatepass"), ".csv")
