"""No compiled function is compiled twice for a constant argument.

A call from one compiled function to another types a constant integer or boolean argument as a literal
(``Literal[int](0)``), and Numba compiles the callee once more for that signature, apart from the one its
other callers use with a run-time value (``int64``). Measured with Numba's compile events on an empty cache
(``benchmarks/compile_time.py``), the particle gather ``_gather_range`` took 10 s a version and was compiled
twice, and so were some thirty kernels of ``bubbling-3d``. The kernels pass such arguments as ``np.int64(0)``
or ``np.bool_(True)``, which are typed as run-time values. This test reads the sources (no compilation): it
lists every call, inside an ``@njit`` function, of a package function compiled on its own (``@njit`` without
``inline="always"``: an inlined callee is typed inside its caller and has no signatures of its own) with a
constant integer or boolean argument written at the call, and compares the list with the calls whose literal
versions are wanted. (A variable that holds a constant where the call is typed can be a literal too; the scan
does not follow variables: the compile events of a cold run are the full check, docs/performance.md.)
"""
from __future__ import annotations

import ast
import sys
from pathlib import Path

import fluidem

ROOT = Path(fluidem.__file__).resolve().parent

# (callee, argument position): constants that select code at compile time, where each value's own compiled
# version is the point (the literal is tested in the callee's body)
WANTED = {
    ("_periodic_row", 12),  # count the row or fill it: two loops in one source
    ("_free_rotor", 2),  # the axis of a free body's rotation, unrolled
    ("_to_faces", 3),  # 2D gas: the face axis of a centre-to-face average
    ("_add_product", 3),  # 2D gas: the face axis of a product
    ("_mg_gauss_seidel", 5),  # 2D multigrid: forward or backward sweep
    ("_faces_of_axis3", 2),  # 3D "cell" exchange: the face axis, tested in the loop over the faces
    ("advance", 42),  # a flat 2D bed (advance_flat): compiled without the variants of beds that are not flat
    ("compute_forces", 29),  # the same for the forces at set-up (compute_forces_flat)
}


def _njit_kind(node: ast.FunctionDef) -> str | None:
    """'own' for @njit(...) compiled on its own, 'inline' for inline="always", None for a Python function."""
    for d in node.decorator_list:
        call = d if isinstance(d, ast.Call) else None
        f = call.func if call else d
        name = f.attr if isinstance(f, ast.Attribute) else getattr(f, "id", None)
        if name != "njit":
            continue
        inline = any(k.arg == "inline" and isinstance(k.value, ast.Constant) and k.value.value == "always"
                     for k in (call.keywords if call else []))
        return "inline" if inline else "own"
    return None


def _module_of(path: Path, level: int, module: str | None) -> Path | None:
    base = path.parent
    for _ in range(level - 1):
        base = base.parent
    target = base.joinpath(*module.split(".")) if module else base
    return target.with_suffix(".py") if target.with_suffix(".py").exists() else None


def _modules():
    """{path: (tree, {local function name: kind}, {imported name: (path, name)}, {alias: path})}."""
    out = {}
    for path in sorted(ROOT.rglob("*.py")):
        tree = ast.parse(path.read_text(), filename=str(path))
        kinds = {n.name: _njit_kind(n) for n in tree.body if isinstance(n, ast.FunctionDef)}
        names, aliases = {}, {}
        for n in tree.body:
            if isinstance(n, ast.ImportFrom) and n.level > 0:
                src = _module_of(path, n.level, n.module)
                for a in n.names:
                    sub = _module_of(path, n.level, f"{n.module}.{a.name}" if n.module else a.name)
                    if sub is not None:
                        aliases[a.asname or a.name] = sub
                    elif src is not None:
                        names[a.asname or a.name] = (src, a.name)
        out[path] = (tree, kinds, names, aliases)
    return out


def _literal(arg: ast.expr) -> bool:
    if isinstance(arg, ast.UnaryOp) and isinstance(arg.op, ast.USub):
        arg = arg.operand
    return isinstance(arg, ast.Constant) and isinstance(arg.value, (bool, int))


def literal_calls():
    """[(file:line, caller, callee, argument position)] of the calls described in the module docstring, those
    of WANTED included."""
    mods = _modules()

    def kind(path, name):
        _, kinds, names, _ = mods[path]
        if name in kinds:
            return kinds[name]
        if name in names:
            src, orig = names[name]
            return mods[src][1].get(orig) if src in mods else None
        return None

    found = []
    for path, (tree, kinds, _, aliases) in mods.items():
        for fn in tree.body:
            if not (isinstance(fn, ast.FunctionDef) and kinds.get(fn.name)):
                continue
            for call in ast.walk(fn):
                if not isinstance(call, ast.Call):
                    continue
                f = call.func
                if isinstance(f, ast.Name):
                    callee, k = f.id, kind(path, f.id)
                elif isinstance(f, ast.Attribute) and isinstance(f.value, ast.Name) and f.value.id in aliases:
                    target = aliases[f.value.id]
                    callee, k = f.attr, mods[target][1].get(f.attr) if target in mods else None
                else:
                    continue
                if k != "own":
                    continue
                for i, arg in enumerate(call.args):
                    if _literal(arg):
                        found.append((f"{path.relative_to(ROOT)}:{call.lineno}", fn.name, callee, i))
    return found


def test_no_compiled_call_passes_a_constant_that_makes_another_signature():
    calls = literal_calls()
    found = [c for c in calls if c[2:] not in WANTED]
    assert {c[2:] for c in calls} >= WANTED  # each wanted literal is still passed somewhere
    assert not found, "constant arguments in calls between compiled functions (pass np.int64(...) or " \
                      "np.bool_(...), or list the argument in WANTED):\n" + "\n".join(map(str, found))


def test_the_scan_sees_such_a_call(tmp_path, monkeypatch):
    """The scan finds a literal start index, and not its np.int64 form (a test that cannot fail is no test)."""
    pkg = tmp_path / "fluidem"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "_k.py").write_text(
        "from numba import njit\nimport numpy as np\n\n"
        "@njit(cache=True)\ndef part(lo, hi):\n    return hi - lo\n\n"
        "@njit(cache=True, inline='always')\ndef inl(lo, hi):\n    return hi - lo\n\n"
        "@njit(cache=True)\ndef whole(n):\n    return part(0, n) + part(np.int64(0), n) + inl(0, n)\n")
    (pkg / "_m.py").write_text(
        "from numba import njit\nfrom . import _k as K\nfrom ._k import part\n\n"
        "@njit(cache=True)\ndef other(n):\n    return K.part(1, n) + part(n, True)\n")
    monkeypatch.setattr(sys.modules[__name__], "ROOT", pkg)
    assert sorted((c, f, i) for _, c, f, i in literal_calls()) == [
        ("other", "part", 0), ("other", "part", 1), ("whole", "part", 0)]
