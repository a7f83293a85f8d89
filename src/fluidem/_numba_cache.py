"""One source stamp for every cached fluidem kernel, so that no cached kernel outlives a change it depends on.

Numba keys each cached function on the file it is defined in: it recompiles a function when that file
changes, not when a function it calls, or a constant it reads, changes in another file. The caller then
keeps the callee's old compiled code. In fluidem that is the rule, not the exception (the soft-sphere
step calls the pair kernels, the list build and the contact laws, each in a file of its own), and it
bites twice: a developer's edit to a callee is silently not used (seen on 2026-11-26: a changed
slab count did not reach the cached ``rebuild``), and an upgraded installation keeps Numba's
``.nbi``/``.nbc`` files in its ``__pycache__`` folders, which pip does not remove.

``install()`` (called at package import, before any kernel module) puts cache locators in front of
Numba's own that serve fluidem's files only: the same places (``NUMBA_CACHE_DIR`` when set, else the
``__pycache__`` beside the source, else the user-wide folder) with one stamp for all of them, a hash
of every source file compiled code can depend on (``kernel_sources``). Any change to one of those
files makes every cached kernel stale, and each is compiled again at its first call (two to four
minutes for a case, docs/performance.md). Editing orchestration modules (``simulation.py``, ``case.py``,
the CLI, the writers) leaves the cache alone.
"""
from __future__ import annotations

import hashlib
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent
_MARK = "_fluidem_package_stamp"


_CUDA_MODULE = re.compile(r"^from numba import (?:[\w ,]*\b)?cuda\b", re.MULTILINE)  # a module of CUDA kernels
_FROM_IMPORT = re.compile(r"^[ \t]*from[ \t]+(\.+)([\w.]*)[ \t]+import[ \t]+(\([^)]*\)|[^\n]*)", re.MULTILINE)


def _relative_imports(path: Path, text: str) -> list[Path]:
    """The package files that the ``from .x import …`` statements in ``text`` (of ``path``) name: the
    modules, or the submodules imported by name (``from . import hertz_mindlin``)."""
    out = []
    for dots, module, names in _FROM_IMPORT.findall(text):
        base = path.parent
        for _ in range(len(dots) - 1):
            base = base.parent
        target = base.joinpath(*module.split(".")) if module else base
        candidates = [target.with_suffix(".py"), target / "__init__.py"] if module else []
        for name in re.findall(r"\b(\w+)\b(?:\s+as\s+\w+)?", names.split("#")[0] if "(" not in names else names):
            candidates.append((target / name).with_suffix(".py"))
        out += [c for c in candidates if c.is_file()]
    return out


def kernel_sources(root: Path = ROOT) -> list[Path]:
    """The files whose change can change compiled code: those defining Numba functions (``njit``, and the
    CUDA kernels and device functions of the modules importing ``numba.cuda`` at their top, cached on disk as the CPU's
    are), and the package modules they import from,
    transitively (constants such as ``contact.base.N_SLOTS`` and
    the cell flags of ``gas.grid`` are frozen into the compiled code that reads them). Sorted."""
    texts = {p.resolve(): p.read_text(encoding="utf-8") for p in root.rglob("*.py")}
    seen = {p for p, t in texts.items() if "njit" in t or _CUDA_MODULE.search(t)}
    todo = list(seen)
    while todo:
        p = todo.pop()
        for q in _relative_imports(p, texts[p]):
            q = q.resolve()
            if q not in seen and q in texts:
                seen.add(q)
                todo.append(q)
    return sorted(seen)


def package_stamp(root: Path = ROOT) -> str:
    """SHA-256 of the paths (relative to ``root``) and contents of ``kernel_sources(root)``."""
    h = hashlib.sha256()
    for p in kernel_sources(root):
        h.update(p.relative_to(root).as_posix().encode())
        h.update(b"\0")
        h.update(p.read_bytes())
        h.update(b"\0")
    return h.hexdigest()


def _locator(base, stamp: str, root: Path):
    """A subclass of Numba's locator ``base`` for the files under ``root``, all with the one ``stamp``."""

    class Locator(base):
        def get_source_stamp(self):
            return stamp

        @classmethod
        def from_function(cls, py_func, py_file):
            try:
                inside = root in Path(py_file).resolve().parents
            except (OSError, ValueError):
                inside = False
            return super().from_function(py_func, py_file) if inside else None

    Locator.__name__ = Locator.__qualname__ = "Fluidem" + base.__name__.lstrip("_")
    setattr(Locator, _MARK, str(root))
    return Locator


def install(root: Path = ROOT, caching=None) -> bool:
    """Put the package-stamped locators first in Numba's list (once per package root); False if this Numba
    lays its cache out differently (then its own per-file stamps stay in force). ``caching``: another module
    of the same layout (numba-cuda's ``numba.cuda.core.caching``, which caches the CUDA kernels), else
    ``numba.core.caching``."""
    if caching is None:
        try:
            from numba.core import caching
        except ImportError:
            return False
    impl = getattr(caching, "CacheImpl", None) or getattr(caching, "_CacheImpl", None)
    names = ("UserProvidedCacheLocator", "InTreeCacheLocator", "UserWideCacheLocator")
    bases = [getattr(caching, n, None) or getattr(caching, "_" + n, None) for n in names]
    if impl is None or not isinstance(getattr(impl, "_locator_classes", None), list) or None in bases:
        return False
    if any(getattr(c, _MARK, None) == str(root) for c in impl._locator_classes):
        return True
    stamp = package_stamp(root)
    impl._locator_classes[:0] = [_locator(b, stamp, root) for b in bases]
    return True
