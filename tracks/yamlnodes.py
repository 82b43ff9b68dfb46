"""Reading YAML as a node tree, so that every error can name its line.

``yaml.compose`` keeps each node's position; these helpers check a node's
shape and convert it, raising `TrackFormatError` with ``file:line`` instead of
letting a KeyError or a yaml traceback escape.
"""

from __future__ import annotations

import math
from pathlib import Path

import yaml

from conesim.tracks.errors import TrackFormatError

_FLOAT_SPECIALS = {".inf", "+.inf", "-.inf", ".nan"}
# libyaml's loader when PyYAML has it (10x faster); both keep node positions.
_LOADER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


def compose(text: str, path: Path) -> yaml.Node | None:
    """The YAML document's root node (None for an empty document)."""
    try:
        return yaml.compose(text, Loader=_LOADER)
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        line = None if mark is None else mark.line + 1
        raise TrackFormatError(
            f"not valid YAML: {exc.problem or exc.context}", path, line
        ) from None
    except yaml.YAMLError as exc:
        raise TrackFormatError(f"not valid YAML: {exc}", path) from None
    except RecursionError:
        raise TrackFormatError("not valid YAML: nested too deeply", path) from None


def line_of(node: yaml.Node) -> int:
    """1-based line where ``node`` starts."""
    return int(node.start_mark.line) + 1


def mapping(node: yaml.Node, path: Path, what: str) -> dict[str, yaml.Node]:
    """A mapping node's entries by key; keys must be unique strings."""
    if not isinstance(node, yaml.MappingNode):
        raise TrackFormatError(f"{what} must be a mapping (key: value)", path, line_of(node))
    entries: dict[str, yaml.Node] = {}
    for key, value in node.value:
        if not isinstance(key, yaml.ScalarNode):
            raise TrackFormatError(f"{what}: keys must be plain names", path, line_of(key))
        if key.value in entries:
            raise TrackFormatError(f"{what}: duplicate key {key.value!r}", path, line_of(key))
        entries[str(key.value)] = value
    return entries


def check_keys(entries: dict[str, yaml.Node], allowed: set[str], path: Path, what: str) -> None:
    """Raise for a key outside ``allowed``, listing the allowed keys."""
    unknown = sorted(set(entries) - allowed)
    if unknown:
        raise TrackFormatError(
            f"{what}: unknown key {unknown[0]!r}; allowed keys: {', '.join(sorted(allowed))}",
            path,
            line_of(entries[unknown[0]]),
        )


def is_null(node: yaml.Node) -> bool:
    """Whether the node is YAML null (``null``, ``~`` or empty)."""
    return isinstance(node, yaml.ScalarNode) and node.tag == "tag:yaml.org,2002:null"


def number(node: yaml.Node, path: Path, what: str) -> float:
    """A finite number from a plain scalar (not a quoted string, not a boolean)."""
    line = line_of(node)
    if not isinstance(node, yaml.ScalarNode):
        raise TrackFormatError(f"{what}: expected a number, found a list or mapping", path, line)
    text = str(node.value)
    quoted = node.style not in (None, "")  # plain: None (Python loader) or "" (libyaml)
    if quoted or node.tag in ("tag:yaml.org,2002:bool", "tag:yaml.org,2002:null"):
        raise TrackFormatError(f"{what}: {text!r} is not a number", path, line)
    if text.lower() in _FLOAT_SPECIALS:
        raise TrackFormatError(f"{what}: {text!r} is not finite", path, line)
    try:
        value = float(text)
    except ValueError:
        raise TrackFormatError(f"{what}: {text!r} is not a number", path, line) from None
    if not math.isfinite(value):
        raise TrackFormatError(f"{what}: {text!r} is not finite", path, line)
    return value


def numbers(node: yaml.Node, count: int, path: Path, what: str) -> list[float]:
    """A list of exactly ``count`` numbers, e.g. ``[x, y]`` or ``[x, y, yaw]``."""
    if not isinstance(node, yaml.SequenceNode) or len(node.value) != count:
        shape = "[x, y]" if count == 2 else "[x, y, yaw]"
        raise TrackFormatError(f"{what}: expected {shape}", path, line_of(node))
    return [number(item, path, what) for item in node.value]


def points(node: yaml.Node, path: Path, what: str) -> list[tuple[float, float, int]]:
    """A list of ``[x, y]`` points (null or empty: none), each with its line."""
    if is_null(node):
        return []
    if not isinstance(node, yaml.SequenceNode):
        raise TrackFormatError(f"{what}: expected a list of [x, y]", path, line_of(node))
    out = []
    for item in node.value:
        x, y = numbers(item, 2, path, what)
        out.append((x, y, line_of(item)))
    return out


def text(node: yaml.Node, path: Path, what: str) -> str:
    """A scalar as text."""
    if not isinstance(node, yaml.ScalarNode) or is_null(node):
        raise TrackFormatError(f"{what}: expected text", path, line_of(node))
    return str(node.value)
