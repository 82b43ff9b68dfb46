"""YAML as plain data with the line of every key, and plain data as YAML.

``read_yaml(path)`` returns the document as plain Python data and a map
from each key's path (``("sensors", "cones", "max_range")``) to its 1-based
line, so that an error found later, when the data is checked against the
dataclasses (``envs.dataclass_io``), can say ``file:line``. Duplicate keys
are refused (YAML itself keeps the last one silently). Numbers follow YAML
1.2 as well as 1.1: ``1e-3`` is a number, not text. ``dump_yaml`` writes
block mappings and lists of scalars in flow style (``[10.0, 12.0]``), floats
exactly (``repr``), so reading the text back gives the same data.
"""

from __future__ import annotations

import os
import re
import stat
from pathlib import Path as FsPath
from typing import Any

import yaml

from conesim.envs.dataclass_io import FieldError, Path

MAX_BYTES = 1 << 20  # [B] a scenario is a page or two; anything larger is not one

Lines = dict[Path, int]
MAX_VALUES = 100_000  # [-] values in a document with its aliases expanded (a sweep of
# hundreds of points holds a few thousand; nested aliases can make 10^7 of 7 lines)
"""Key path -> the 1-based line of the key."""


class _Loader(yaml.SafeLoader):
    """The safe loader, with YAML 1.2's exponent floats (``1e-3``) as numbers."""


_Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9][0-9_]*)(?:\.[0-9_]*)?[eE][-+]?[0-9]+$"),
    list("-+0123456789"),
)


def _lines(node: yaml.Node, path: Path, out: Lines, source: str) -> None:
    """Record every key's line under ``node``; refuse duplicate keys."""
    if isinstance(node, yaml.MappingNode):
        seen: set[str] = set()
        for key, value in node.value:
            name = key.value if isinstance(key, yaml.ScalarNode) else None
            line = key.start_mark.line + 1
            if name in seen:
                raise FieldError((*path, str(name)), "duplicate key", f"{source}:{line}")
            if name is not None:
                seen.add(name)
                out[(*path, name)] = line
                _lines(value, (*path, name), out, source)
    elif isinstance(node, yaml.SequenceNode):
        for i, item in enumerate(node.value):
            out[(*path, i)] = item.start_mark.line + 1
            _lines(item, (*path, i), out, source)


def parse_yaml(text: str, source: str) -> tuple[Any, Lines]:
    """The document's data and its keys' lines; ``source`` names it in errors.

    Raises:
        FieldError: not valid YAML, or a duplicate key (with the line).
    """
    try:
        node = yaml.compose(text, Loader=_Loader)
        data = yaml.load(text, Loader=_Loader)  # a SafeLoader
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        where = source if mark is None else f"{source}:{mark.line + 1}"
        raise FieldError((), f"not valid YAML: {exc.problem or exc.context}", where) from None
    except yaml.YAMLError as exc:
        raise FieldError((), f"not valid YAML: {exc}", source) from None
    except RecursionError:
        raise FieldError((), "not valid YAML: nested too deeply", source) from None
    lines: Lines = {}
    if node is not None:
        _check_size(node, source)
        _lines(node, (), lines, source)
    return data, lines


def _check_size(root: yaml.Node, source: str) -> None:
    """Refuse a document of more than ``MAX_VALUES`` values, aliases expanded (what
    the line map and the checks would walk; a recursive alias never ends)."""
    stack, count = [root], 0
    while stack:
        node = stack.pop()
        count += 1
        if count > MAX_VALUES:
            raise FieldError((), f"more than {MAX_VALUES} values with its aliases expanded", source)
        if isinstance(node, yaml.SequenceNode):
            stack.extend(node.value)
        elif isinstance(node, yaml.MappingNode):
            stack.extend(v for pair in node.value for v in pair)


def read_yaml(path: str | os.PathLike[str]) -> tuple[Any, Lines]:
    """A YAML file's data and its keys' lines.

    Only a regular UTF-8 text file of at most ``MAX_BYTES`` is read.

    Raises:
        FieldError: the file cannot be read, or is not valid YAML.
    """
    file = FsPath(path)
    source = os.fspath(path)
    try:
        mode = file.stat().st_mode
        if not stat.S_ISREG(mode):
            kind = "a directory" if stat.S_ISDIR(mode) else "not a regular file"
            raise FieldError((), f"is {kind}, not a scenario file", source)
        with file.open("rb") as stream:
            data = stream.read(MAX_BYTES + 1)
    except FileNotFoundError:
        raise FieldError((), "no such file", source) from None
    except OSError as exc:
        raise FieldError((), f"cannot read ({exc.strerror or exc})", source) from None
    if len(data) > MAX_BYTES:
        raise FieldError((), f"larger than {MAX_BYTES} bytes, not a scenario file", source)
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise FieldError((), "not UTF-8 text (a binary file?)", source) from None
    return parse_yaml(text, source)


def parse_value(text: str) -> Any:
    """One value as YAML reads it: ``0.7``, ``true``, ``[10, 12]``, ``colour``, ``null``.

    Raises:
        FieldError: not a valid YAML value.
    """
    return parse_yaml(text, "value")[0]


class _Dumper(yaml.SafeDumper):
    """Block mappings and lists; a list of scalars in flow style (a matrix: a row a line)."""


def _represent_list(dumper: yaml.SafeDumper, items: list[Any]) -> yaml.Node:
    flat = not any(isinstance(v, dict | list) for v in items)
    return dumper.represent_sequence("tag:yaml.org,2002:seq", items, flow_style=flat)


_Dumper.add_representer(list, _represent_list)


def dump_yaml(data: Any, *, flow: bool = False) -> str:
    """Plain data as YAML text that ``parse_yaml`` reads back as the same data.

    ``flow``: on one line (``{generate: {seed: 3}}``), for labels.
    """
    return yaml.dump(
        data,
        Dumper=yaml.SafeDumper if flow else _Dumper,
        sort_keys=False,
        default_flow_style=flow,
        allow_unicode=True,
        width=10**9 if flow else 80,
    )
