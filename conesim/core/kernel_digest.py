"""What a compiled kernel's machine code depends on, as one digest of the code in memory.

numba compiles a kernel from its bytecode, the values of the globals it
reads (frozen as constants), its closure, and the kernels it calls, each
compiled the same way. Its on-disk cache checks only the kernel's own source
file, so the cached code of a kernel that calls a kernel from another file,
or reads a constant defined there, goes stale when that file is edited.
:func:`digest` hashes all of it, followed through every kernel the kernel can
reach, and :mod:`conesim.core.kernel_cache` files the cached code under it.

What is followed, from each function reached:

- every global it names (``co_names``, nested code objects included),
  resolved in its module; a module or class of one of ``packages`` is looked
  into for the names too (``kernels.median``, ``a.b.c``, ``Side.LEFT``);
  other modules (numpy, math) are left to their version, as numba's own
  cache does;
- a jitted function (any package) is followed into its Python function, and
  so is a plain function of one of ``packages`` (``register_jitable``);
- everything else is a value: numbers, strings, tuples, arrays and enums by
  value, types and outside functions by name.

The digest hashes code objects (bytecode, constants, names), not files:
what this process compiles is the code it imported, whatever its file says
now, and a docstring or comment elsewhere in the file changes nothing.
"""

from __future__ import annotations

import enum
import functools
import hashlib
import types
from collections.abc import Callable, Iterable, Iterator
from typing import Any

import numpy as np
from numba.core.types import Type as NumbaType
from numba.extending import is_jitted

_LITERALS = (bool, int, float, complex, str, bytes, type(None), type(Ellipsis))


def digest(func: Callable[..., Any], packages: Iterable[str]) -> str:
    """A hex digest of ``func``'s code and of everything it can reach, as above.

    Args:
        func: the kernel's Python function (a dispatcher's ``py_func``).
        packages: the top-level packages whose modules and plain functions
            are followed (the kernels' own).
    """
    within = frozenset(packages)
    parts = sorted(_describe_function(f, within) for f in reachable(func, within))
    return hashlib.sha256("\n".join(parts).encode()).hexdigest()


def code_size(func: Callable[..., Any], packages: Iterable[str]) -> int:
    """Bytes of bytecode in ``func`` and everything it can reach: a proxy for its compile time."""
    return sum(
        len(code.co_code)
        for f in reachable(func, frozenset(packages))
        for code in _code_objects(f.__code__)
    )


def reachable(func: Callable[..., Any], packages: frozenset[str]) -> list[types.FunctionType]:
    """``func`` and every Python function it can call when compiled, each once."""
    seen: dict[int, types.FunctionType] = {}
    stack = [_python_function(func)]
    while stack:
        f = stack.pop()
        if f is None or id(f) in seen:
            continue
        seen[id(f)] = f
        for _, value in _dependencies(f, packages):
            stack.append(_followed(value, packages))
    return list(seen.values())


def _python_function(value: Any) -> types.FunctionType | None:
    if is_jitted(value):
        value = value.py_func
    return value if isinstance(value, types.FunctionType) else None


def _followed(value: Any, packages: frozenset[str]) -> types.FunctionType | None:
    """The Python function behind ``value`` when the walk goes into it, else None."""
    if is_jitted(value):
        return _python_function(value)
    if isinstance(value, types.FunctionType) and _top(value.__module__) in packages:
        return value
    return None


def _top(module: str | None) -> str:
    return (module or "").split(".")[0]


def _scope(value: Any, packages: frozenset[str]) -> dict[str, Any] | None:
    """The namespace of a module or class of ``packages``, else None."""
    if isinstance(value, types.ModuleType) and _top(value.__name__) in packages:
        return vars(value)
    if isinstance(value, type) and _top(value.__module__) in packages:
        return dict(vars(value))
    return None


def _dependencies(f: types.FunctionType, packages: frozenset[str]) -> Iterator[tuple[str, Any]]:
    """(name, value) of the globals ``f`` names, its closure's cells and its defaults."""
    names = sorted({name for code in _code_objects(f.__code__) for name in code.co_names})
    found: list[tuple[str, Any]] = [(n, f.__globals__[n]) for n in names if n in f.__globals__]
    looked_into: set[int] = set()
    while found:
        name, value = found.pop()
        scope = _scope(value, packages)
        if scope is not None and id(value) not in looked_into:
            looked_into.add(id(value))
            found += [(f"{name}.{n}", scope[n]) for n in names if n in scope]
        if not isinstance(value, types.ModuleType):
            yield name, value
    for i, cell in enumerate(f.__closure__ or ()):
        try:
            yield f"<cell {i}>", cell.cell_contents
        except ValueError:  # an empty cell
            continue
    for i, default in enumerate(f.__defaults__ or ()):
        yield f"<default {i}>", default
    for key, default in sorted((f.__kwdefaults__ or {}).items()):
        yield f"<default {key}>", default


def _describe_function(f: types.FunctionType, packages: frozenset[str]) -> str:
    """One function's own share of the digest: its code and the values it reads
    (a function it calls by name only: the walk describes that one itself)."""
    lines = [f"{f.__module__}.{f.__qualname__}", _describe_code(f.__code__)]
    lines += sorted(f"{name}={_describe_value(v)}" for name, v in _dependencies(f, packages))
    return "\n".join(lines)


def _code_objects(code: types.CodeType) -> Iterator[types.CodeType]:
    yield code
    for const in code.co_consts:
        if isinstance(const, types.CodeType):
            yield from _code_objects(const)


def _describe_code(code: types.CodeType) -> str:
    """Everything numba compiles from a code object; line numbers and the file left out."""
    consts = ",".join(
        _describe_code(c) if isinstance(c, types.CodeType) else _describe_value(c)
        for c in code.co_consts
    )
    fields = (
        code.co_argcount,
        code.co_posonlyargcount,
        code.co_kwonlyargcount,
        code.co_flags,
        code.co_code.hex(),
        code.co_names,
        code.co_varnames,
        code.co_freevars,
        code.co_cellvars,
        code.co_exceptiontable.hex(),
    )
    return f"code{fields!r}[{consts}]"


@functools.singledispatch
def _describe_value(value: Any) -> str:
    """A value as the kernel sees it; the same in every process (no addresses)."""
    if is_jitted(value):
        f = value.py_func
        options = sorted(getattr(value, "targetoptions", {}).items())
        return f"jitted:{f.__module__}.{f.__qualname__}{options!r}"
    if isinstance(value, _LITERALS):
        return f"{type(value).__name__}:{value!r}"
    if isinstance(value, enum.Enum):
        return f"enum:{type(value).__module__}.{type(value).__qualname__}.{value.name}:" + (
            _describe_value(value.value)
        )
    if isinstance(value, tuple):
        return f"{type(value).__qualname__}(" + ",".join(map(_describe_value, value)) + ")"
    if isinstance(value, frozenset):
        return "frozenset{" + ",".join(sorted(map(_describe_value, value))) + "}"
    if isinstance(value, (slice, NumbaType)):
        return f"{type(value).__name__}:{value}"
    name = getattr(value, "__qualname__", None) or getattr(value, "__name__", None)
    if isinstance(name, str):  # a type or a function from outside the walk: by name
        return f"{type(value).__name__}:{getattr(value, '__module__', None)}.{name}"
    return f"object:{type(value).__module__}.{type(value).__qualname__}"


@_describe_value.register
def _(value: np.ndarray) -> str:
    data = hashlib.sha256(np.ascontiguousarray(value).tobytes()).hexdigest()
    return f"ndarray:{value.dtype.str}:{value.shape}:{data}"


@_describe_value.register
def _(value: np.generic) -> str:
    return f"{value.dtype.str}:{value!r}"


@_describe_value.register
def _(value: np.dtype) -> str:
    return f"dtype:{value.str}:{value.descr!r}"
