"""Frozen dataclasses from plain data (YAML, JSON, dicts) and back, with errors by path.

``build(cls, data)`` makes a ``cls`` from a mapping, field by field after
its type hints: numbers, booleans, text, ``Literal`` choices, enums (by
name, or a ``StrEnum`` by value), ``X | None``, tuples (from lists) and
nested dataclasses (from nested mappings). Given a ``base`` instance, the
fields the mapping leaves out are the base's, nested ones too, so a mapping
is a set of changes to a preset. ``plain(obj)`` is the inverse: a mapping
of every field, which ``build`` turns back into an equal object.

Why by hand and not a library: the configs already validate themselves in
``__post_init__`` with messages that name the field and its range; what is
missing is only the path to the field in a larger file (and its line), the
strict types that keep a run bit for bit (an int where a float is meant is
made a float; a boolean is never a number) and unknown keys refused with
the allowed ones listed. Every problem is one ``FieldError``: a path
(``sensors.cones.max_range``), a reason, and where it came from
(``file:line``) once the reader knows.
"""

from __future__ import annotations

import dataclasses
import enum
import numbers
import re
import types
import typing
from collections.abc import Mapping, Sequence
from typing import Any, TypeVar

T = TypeVar("T")
Path = tuple[str | int, ...]
"""Keys from the root to a value: ("sensors", "gps", "dropouts", 0)."""

Hidden = Mapping[type, frozenset[str]]
"""Fields of a class that plain data may not set (kept from the base), by class."""


def dotted(path: Path) -> str:
    """``sensors.gps.dropouts[0]`` for ("sensors", "gps", "dropouts", 0)."""
    out = ""
    for key in path:
        out += f"[{key}]" if isinstance(key, int) else (f".{key}" if out else str(key))
    return out


class FieldError(ValueError):
    """A value in plain data that cannot be used: one line, path first.

    Args:
        path: where the value is.
        reason: what is wrong (the allowed keys, range or type).
        where: the file and line, or the command-line option, it came from.
    """

    def __init__(self, path: Path, reason: str, where: str | None = None) -> None:
        self.path = tuple(path)
        self.reason = reason
        self.where = where
        parts = [p for p in (where, dotted(self.path)) if p]
        super().__init__(": ".join([*parts, reason]))

    def __reduce__(self) -> tuple[Any, ...]:
        return type(self), (self.path, self.reason, self.where)

    def located(self, where: str | None) -> FieldError:
        """The same error, said to come from ``where`` (a file:line or an option)."""
        return FieldError(self.path, self.reason, where)


def _type_name(value: Any) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, numbers.Number):
        return "a number"
    if isinstance(value, str):
        return "text"
    if isinstance(value, Mapping):
        return "a mapping"
    if isinstance(value, Sequence):
        return "a list"
    return type(value).__name__


def _wrong(path: Path, expected: str, value: Any) -> FieldError:
    return FieldError(path, f"expected {expected}, got {value!r} ({_type_name(value)})")


def _is_bool(value: Any) -> bool:
    return isinstance(value, bool) or type(value).__name__ == "bool_"  # numpy's too


def convert(value: Any, hint: Any, path: Path = (), hidden: Hidden | None = None) -> Any:
    """``value`` as the type ``hint`` names (see the module docstring).

    Raises:
        FieldError: the value is not of that type (the message names the type).
    """
    origin = typing.get_origin(hint)
    args = typing.get_args(hint)
    if hint is Any:
        return value
    if origin in (typing.Union, types.UnionType):
        if value is None and type(None) in args:
            return None
        options = [a for a in args if a is not type(None)]
        if len(options) == 1:
            try:
                return convert(value, options[0], path, hidden)
            except FieldError as exc:
                if type(None) not in args:
                    raise
                raise FieldError(exc.path, f"{exc.reason}, or null") from None
        for option in options:
            try:
                return convert(value, option, path, hidden)
            except FieldError:
                continue
        raise _wrong(path, " or ".join(_describe(o) for o in args), value)
    if origin is typing.Literal:
        if isinstance(value, str | int) and not _is_bool(value) and value in args:
            return value
        raise FieldError(path, f"expected one of {', '.join(map(repr, args))}, got {value!r}")
    if hint is bool:
        if _is_bool(value):
            return bool(value)
        raise _wrong(path, "true or false", value)
    if hint is int:
        if isinstance(value, numbers.Integral) and not _is_bool(value):
            return int(value)
        raise _wrong(path, "an integer", value)
    if hint is float:
        if isinstance(value, numbers.Real) and not _is_bool(value):
            return float(value)
        raise _wrong(path, "a number", value)
    if hint is str:
        if isinstance(value, str):
            return value
        raise _wrong(path, "text", value)
    if isinstance(hint, type) and issubclass(hint, enum.Enum):
        return _enum(value, hint, path)
    if origin is tuple:
        return _tuple(value, args, path, hidden)
    if isinstance(hint, type) and dataclasses.is_dataclass(hint):
        if isinstance(value, hint):
            return value
        return build(hint, value, path=path, hidden=hidden)
    raise TypeError(f"{dotted(path)}: no conversion to {hint!r}")  # a config this does not know


def _describe(hint: Any) -> str:
    names = {bool: "true or false", int: "an integer", float: "a number", str: "text"}
    if hint in names:
        return names[hint]
    if hint is type(None):
        return "null"
    return getattr(hint, "__name__", repr(hint))


def _enum(value: Any, cls: type[enum.Enum], path: Path) -> enum.Enum:
    """An enum member by its name (or, for a text enum, its value)."""
    if isinstance(value, cls):
        return value
    by_value = issubclass(cls, str)
    names = [str(m.value) if by_value else m.name for m in cls]
    if isinstance(value, str):
        for member in cls:
            if value == (member.value if by_value else member.name):
                return member
    raise FieldError(path, f"expected one of {', '.join(names)}, got {value!r}")


def _tuple(value: Any, args: tuple[Any, ...], path: Path, hidden: Hidden | None) -> tuple[Any, ...]:
    """A tuple from a list: ``tuple[X, ...]`` of any length, ``tuple[X, Y]`` of exactly two."""
    if isinstance(value, str | bytes) or not isinstance(value, Sequence):
        shape = "a list" if len(args) == 2 and args[1] is Ellipsis else f"a list of {len(args)}"
        raise _wrong(path, shape, value)
    if len(args) == 2 and args[1] is Ellipsis:
        return tuple(convert(v, args[0], (*path, i), hidden) for i, v in enumerate(value))
    if len(value) != len(args):
        raise FieldError(path, f"expected a list of {len(args)} items, got {len(value)}")
    return tuple(
        convert(v, a, (*path, i), hidden) for i, (v, a) in enumerate(zip(value, args, strict=True))
    )


def settable(cls: type, hidden: Hidden | None = None) -> list[str]:
    """The fields of ``cls`` that plain data may set, in declaration order."""
    skip = (hidden or {}).get(cls, frozenset())
    return [f.name for f in dataclasses.fields(cls) if f.init and f.name not in skip]


def default_of(cls: type, name: str) -> Any:
    """The default of field ``name`` of ``cls`` (its factory's value)."""
    spec = next(f for f in dataclasses.fields(cls) if f.name == name)
    if spec.default_factory is not dataclasses.MISSING:
        return spec.default_factory()
    return spec.default


_OWNER_FIELD = re.compile(r"^\w+\.(\w+)\b")


def build(
    cls: type[T],
    data: Any,
    *,
    base: T | None = None,
    path: Path = (),
    hidden: Hidden | None = None,
) -> T:
    """A ``cls`` from a mapping of its fields (the rest from ``base`` or the defaults).

    Args:
        cls: a dataclass.
        data: field name -> plain value.
        base: the instance the mapping changes; None: ``cls``'s defaults.
        path: where ``data`` is, for the errors.
        hidden: fields the mapping may not set, by class.

    Raises:
        FieldError: an unknown key (the allowed ones listed), a value of the
            wrong type, or the class's own check failing (its message, at the
            field it names when it names one).
    """
    if not isinstance(data, Mapping):
        raise _wrong(path, f"a mapping of {cls.__name__} fields", data)
    names = settable(cls, hidden)
    for key in data:
        if key not in names:
            raise FieldError((*path, key), f"unknown key {key!r}; allowed keys: {', '.join(names)}")
    hints = typing.get_type_hints(cls)
    values: dict[str, Any] = {}
    for name, value in data.items():
        hint = hints[name]
        if isinstance(hint, type) and dataclasses.is_dataclass(hint) and isinstance(value, Mapping):
            inner = getattr(base, name) if base is not None else default_of(cls, name)
            values[name] = build(hint, value, base=inner, path=(*path, name), hidden=hidden)
        else:
            values[name] = convert(value, hint, (*path, name), hidden)
    try:
        if base is not None:
            return dataclasses.replace(base, **values)  # type: ignore[type-var]
        return cls(**values)
    except (ValueError, TypeError) as exc:
        if isinstance(exc, FieldError):
            raise
        reason = str(exc)
        named = _OWNER_FIELD.match(reason)
        at = (*path, named.group(1)) if named and named.group(1) in names else path
        raise FieldError(at, reason) from None


def plain(obj: Any, hidden: Hidden | None = None) -> Any:
    """Plain data of a value: a dataclass as a mapping of every settable field,
    tuples as lists, enums by name (a text enum by value); ``build`` reverses it."""
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return {name: plain(getattr(obj, name), hidden) for name in settable(type(obj), hidden)}
    if isinstance(obj, enum.Enum):
        return obj.value if isinstance(obj, str) else obj.name
    if isinstance(obj, Mapping):
        return {key: plain(value, hidden) for key, value in obj.items()}
    if isinstance(obj, tuple | list):
        return [plain(v, hidden) for v in obj]
    return obj
