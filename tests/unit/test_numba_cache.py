"""One source stamp for all cached kernels (``fluidem._numba_cache``): a change to any file compiled code
depends on makes every cached kernel stale; orchestration modules do not count."""
import shutil

import numba
import numpy as np

from fluidem import _numba_cache as C
from fluidem.particles import _neighbours_kernels, _softsphere_kernels


def _names(root):
    return {p.relative_to(root).as_posix() for p in C.kernel_sources(root)}


def test_kernel_sources_are_the_compiled_files_and_what_they_import():
    names = _names(C.ROOT)
    for f in ("particles/_softsphere_kernels.py", "particles/_pair_kernels.py", "particles/contact/hertz_mindlin.py",
              "coupling/drag/gidaspow.py", "gas/_solver_kernels.py"):
        assert f in names, f"{f}: defines compiled functions"
    for f in ("particles/_softsphere_cuda.py", "particles/_neighbours_cuda.py", "coupling/_paired_cuda.py",
              "coupling/_voidage_cuda.py", "coupling/_paired3d_cuda.py", "coupling/_voidage3d_cuda.py"):
        assert f in names, f"{f}: CUDA kernels, cached on disk"
    for f in ("particles/contact/base.py", "gas/grid.py"):  # constants frozen into compiled code (N_SLOTS, cell flags)
        assert f in names, f"{f}: imported by kernel files"
    for f in ("simulation.py", "case.py", "cli.py", "io/snapshots.py", "plotting/figures/__init__.py",
              "analysis/probes.py"):
        assert f not in names, f"{f}: orchestration, no compiled code depends on it"


def test_the_stamp_follows_kernel_sources_and_their_constants_only(tmp_path):
    root = tmp_path / "fluidem"
    shutil.copytree(C.ROOT, root, ignore=shutil.ignore_patterns("__pycache__", "*.nbi", "*.nbc"))
    first = C.package_stamp(root)
    assert C.package_stamp(root) == first
    sim = root / "simulation.py"
    sim.write_text(sim.read_text() + "\n# an orchestration edit\n")
    assert C.package_stamp(root) == first
    base = root / "particles" / "contact" / "base.py"
    base.write_text(base.read_text() + "\n# a constant's module\n")
    second = C.package_stamp(root)
    assert second != first
    callee = root / "particles" / "_neighbours_kernels.py"
    callee.write_text(callee.read_text().replace("PARTICLES_PER_SLAB = 150", "PARTICLES_PER_SLAB = 151"))
    assert C.package_stamp(root) not in (first, second)


@numba.njit(cache=True)
def _not_fluidem(x):
    return x + 1.0


def test_fluidem_kernels_carry_the_package_stamp_and_other_code_does_not():
    assert C.install() is True  # the package installed it at import; a second call adds nothing
    stamp = C.package_stamp()
    for kernel in (_neighbours_kernels.build_pairs, _softsphere_kernels.advance):
        locator = kernel._cache._impl._locator
        assert type(locator).__name__.startswith("Fluidem")
        assert locator.get_source_stamp() == stamp
    other = _not_fluidem._cache._impl._locator
    assert not type(other).__name__.startswith("Fluidem")
    assert _not_fluidem(np.float64(1.0)) == 2.0
    from numba.core import caching

    impl = getattr(caching, "CacheImpl", None) or getattr(caching, "_CacheImpl")
    assert sum(c.__name__.startswith("Fluidem") for c in impl._locator_classes) == 3
