"""Name → class registries for swappable physics (contact models, drag laws, boundaries).

A case file chooses a model by name; the schema builds its allowed names from
``Registry.names()``, so adding a model is one file plus one ``@register`` line.
"""
from __future__ import annotations

import difflib
from typing import Callable, Generic, TypeVar

T = TypeVar("T")


class Registry(Generic[T]):
    """A named collection of model classes with helpful lookup errors."""

    def __init__(self, kind: str):
        self.kind = kind
        self._items: dict[str, T] = {}

    def register(self, name: str) -> Callable[[T], T]:
        def deco(obj: T) -> T:
            if name in self._items:
                raise ValueError(f"{self.kind} {name!r} is registered twice")
            self._items[name] = obj
            return obj

        return deco

    def get(self, name: str) -> T:
        try:
            return self._items[name]
        except KeyError:
            hint = difflib.get_close_matches(name, self._items, n=1)
            extra = f"; did you mean {hint[0]!r}?" if hint else ""
            raise KeyError(
                f"unknown {self.kind} {name!r}: allowed are {', '.join(sorted(self._items))}{extra}"
            ) from None

    def names(self) -> list[str]:
        return sorted(self._items)

    def items(self):
        return self._items.items()

    def __contains__(self, name: str) -> bool:
        return name in self._items


def import_submodules(package_name: str, package_path, skip=("base",)) -> None:
    """Import every module of a package whose name does not start with ``_`` (and is not in ``skip``), so that
    each model file registers itself: adding a model is adding its file."""
    import importlib
    import pkgutil

    for info in sorted(pkgutil.iter_modules(package_path), key=lambda m: m.name):
        if not info.name.startswith("_") and info.name not in skip:
            importlib.import_module(f"{package_name}.{info.name}")


def compiled_switch(name: str, cases: dict[int, Callable], args: tuple[str, ...], code: str, default: str,
                    module: str, source_file: str, jit: Callable | None = None, **njit_options):
    """A compiled function ``name(*args)`` that calls ``cases[c](*args)`` for the integer ``c`` the expression
    ``code`` gives (``"int(p[0])"``), and returns ``default`` for any other code.

    This is the ``switch (model)`` of LAMMPS written from a registry: the same ``if c == 1: return …`` chain a
    hand-written dispatch module holds, so that the callees inline and the callers vectorise as before, while
    the list of models is the registry's alone. Numba has no dispatch over a table of functions that keeps
    them inlined (first-class function objects are called through pointers), hence the source text. The
    function is compiled with ``njit(cache=True, **njit_options)`` and cached as if defined in
    ``source_file``; fluidem's cache stamp (``_numba_cache``) covers every model file, so a new model
    recompiles it. ``jit``: another decorator to compile it with instead (the CUDA dispatch passes
    ``cuda.jit(device=True)`` and device versions of the cases); ``njit_options`` are then not used.
    """
    from numba import njit

    arglist = ", ".join(args)
    lines = [f"def {name}({arglist}):", f"    c = {code}"]
    glob = {"__name__": module}
    for c in sorted(cases):
        callee = f"_case_{c}"
        glob[callee] = cases[c]
        lines += [f"    if c == {c}:", f"        return {callee}({arglist})"]
    lines.append(f"    return {default}")
    exec(compile("\n".join(lines) + "\n", source_file, "exec"), glob)  # noqa: S102 - source built above
    func = glob[name]
    func.__qualname__ = name
    if jit is not None:
        return jit(func)
    return njit(cache=True, **njit_options)(func)
