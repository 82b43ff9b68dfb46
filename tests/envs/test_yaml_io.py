"""Tests for envs.yaml_io: data with the line of every key, and YAML written back."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from conesim.envs.dataclass_io import FieldError
from conesim.envs.yaml_io import (
    MAX_BYTES,
    MAX_VALUES,
    dump_yaml,
    parse_value,
    parse_yaml,
    read_yaml,
)

TEXT = """\
track: autocross
sensors:
  profile: rtk
  cones:
    max_range: 20.0
faults:
  gps:
    dropouts:
    - [10.0, 12.0]
"""


def test_every_key_has_its_line() -> None:
    """Keys and list items map to their 1-based lines."""
    data, lines = parse_yaml(TEXT, "s.yaml")
    assert data["faults"]["gps"]["dropouts"] == [[10.0, 12.0]]
    assert lines[("track",)] == 1
    assert lines[("sensors", "cones", "max_range")] == 5
    assert lines[("faults", "gps", "dropouts", 0)] == 9


def test_a_duplicate_key_is_refused_with_its_line() -> None:
    """YAML keeps the last of two equal keys silently; here it is an error."""
    with pytest.raises(FieldError) as info:
        parse_yaml("laps: 1\nseed: 2\nlaps: 3\n", "s.yaml")
    assert str(info.value) == "s.yaml:3: laps: duplicate key"


def test_nested_aliases_past_the_value_limit_are_refused() -> None:
    """Seven lines of aliases ten deep expand to 10^7 values: refused by name, at
    once; five levels (1.1e5 values with the lists) too, four (1.1e4) read."""

    def nested(levels: int) -> str:
        lines = ["a0: &a0 [x, x, x, x, x, x, x, x, x, x]"]
        lines += [f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * 10)}]" for i in range(1, levels)]
        return "\n".join(lines) + "\n"

    for levels in (7, 5):
        with pytest.raises(FieldError, match=f"more than {MAX_VALUES} values with its aliases"):
            parse_yaml(nested(levels), "b.yaml")
    data, _ = parse_yaml(nested(4), "b.yaml")
    assert len(data["a3"]) == 10 and data["a3"][0][0][0] == ["x"] * 10
    with pytest.raises(FieldError, match="aliases expanded"):  # an alias in itself
        parse_yaml("a: &a [*a]\n", "r.yaml")


def test_invalid_yaml_names_the_line() -> None:
    """A syntax error is one line with the file and line."""
    with pytest.raises(FieldError, match=r"^s.yaml:2: not valid YAML: "):
        parse_yaml("laps: 1\nseed: a: 2\n", "s.yaml")


@pytest.mark.parametrize(
    ("text", "value"),
    [("1e-3", 1e-3), ("2E+2", 200.0), ("0.7", 0.7), ("3", 3), ("true", True), ("null", None),
     ("[10, 12]", [10, 12]), ("colour", "colour"), (".inf", math.inf), ("", None)],
)  # fmt: skip
def test_values_read_as_yaml_with_exponent_floats(text: str, value: object) -> None:
    """--set values are YAML; 1e-3 is a number (YAML 1.2), not the text PyYAML makes it."""
    got = parse_value(text)
    assert got == value and type(got) is type(value)


def test_written_yaml_reads_back_exactly() -> None:
    """Floats round-trip bit for bit, infinity too; lists of numbers are one line."""
    data = {"a": math.radians(0.25), "b": 1e-5, "c": math.inf, "d": [[1.0, 2.0]], "e": [],
            "f": {"g": None, "h": "x"}}  # fmt: skip
    text = dump_yaml(data)
    assert parse_yaml(text, "x")[0] == data
    assert "- [1.0, 2.0]" in text and "e: []" in text


def test_read_refuses_what_is_no_scenario_file(tmp_path: Path) -> None:
    """A missing file, a directory, a huge file and a binary one: one line each."""
    cases = {
        "missing.yaml": "no such file",
        ".": "is a directory, not a scenario file",
    }
    for name, message in cases.items():
        with pytest.raises(FieldError, match=message):
            read_yaml(tmp_path / name)
    big = tmp_path / "big.yaml"
    big.write_text("#" * (MAX_BYTES + 1))
    with pytest.raises(FieldError, match="larger than"):
        read_yaml(big)
    binary = tmp_path / "bin.yaml"
    binary.write_bytes(b"\xff\xfe\x00")
    with pytest.raises(FieldError, match="not UTF-8"):
        read_yaml(binary)
