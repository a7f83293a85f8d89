"""The working tree's kernels against an earlier commit's, in one process, on the same problem.

    NUMBA_NUM_THREADS=1 python benchmarks/ab_kernels.py --base 1a6ee39 --problem bed10k
    NUMBA_NUM_THREADS=1 python benchmarks/ab_kernels.py --base 1a6ee39 --problem coupled --from RUN_DIR

The shared machine's speed drifts by up to 2x within minutes, so timings of two versions taken
in separate runs minutes apart compare badly. Here the package of commit ``--base`` is extracted
(``git archive``) as ``fluidem_base`` next to the installed ``fluidem``, both build the same
problem, and they advance it in alternating bursts (the order swapped every round): the totals,
medians and fastest bursts meet the same swings. At the end the two states are compared: a
change meant to leave the results bitwise the same must print ``same state: True``.

Problems: ``bed10k`` the 10,000-sphere bench bed of ``fluidem bench`` (``--per`` DEM steps a
burst); ``coupled`` a coupled run resumed from the checkpoint of ``--from`` (a run directory,
e.g. ``fluidem run tsuji-jet --until 1.5 --out runs/tj``; copied, not changed), ``--per`` gas
steps a burst.
"""
from __future__ import annotations

import argparse
import importlib
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def base_package(rev: str, where: Path) -> None:
    """src/fluidem of commit ``rev`` as the package ``fluidem_base`` in ``where``."""
    tar = subprocess.run(["git", "-C", str(ROOT), "archive", rev, "src/fluidem"], check=True, capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(where)], input=tar, check=True)
    pkg = where / "fluidem_base"
    (where / "src" / "fluidem").rename(pkg)
    for f in pkg.rglob("*.py"):  # its data files (cases, beds) from its own folder
        text = f.read_text()
        if 'resources.files("fluidem")' in text:
            f.write_text(text.replace('resources.files("fluidem")', 'resources.files("fluidem_base")'))


def _drop_unknown_state(restart: Path, mod) -> None:
    """Remove the particle arrays an older package does not know (e.g. ``state/ids``) from a checkpoint
    copy, so that it resumes a checkpoint written by a newer one."""
    import h5py

    known = set(importlib.import_module(f"{mod.__name__}.state").ParticleState.__dataclass_fields__)
    with h5py.File(restart, "a") as f:
        for k in list(f.get("state", {})):
            if k not in known:
                del f["state"][k]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--base", required=True, help="the earlier commit (any git revision)")
    ap.add_argument("--problem", choices=("bed10k", "coupled"), default="bed10k")
    ap.add_argument("--from", dest="run_dir", help="run directory with restart.h5 (problem 'coupled')")
    ap.add_argument("--bursts", type=int, default=20, help="bursts per version")
    ap.add_argument("--per", type=int, default=0, help="steps per burst (default 200 DEM / 50 gas steps)")
    ap.add_argument("--threads", type=int, default=None,
                    help="threads of the coupled run (default: the case's, one per 1200 particles)")
    args = ap.parse_args()
    if args.problem == "coupled" and not args.run_dir:
        ap.error("--problem coupled needs --from RUN_DIR")
    tmp = Path(tempfile.mkdtemp(prefix="ab_kernels_"))
    try:
        base_package(args.base, tmp)
        sys.path.insert(0, str(tmp))
        mods = {"base": importlib.import_module("fluidem_base"), "tree": importlib.import_module("fluidem")}
        runs = {}
        for name, mod in mods.items():
            if args.problem == "bed10k":
                eng = importlib.import_module(f"{mod.__name__}.bench").load_bed_engine(10000)
                per = args.per or 200
                runs[name] = (eng, lambda e=eng, k=per: e.advance(k), 10000 * per)
            else:
                copy = tmp / f"run_{name}"
                shutil.copytree(args.run_dir, copy)
                _drop_unknown_state(copy / "restart.h5", mod)
                sim = mod.Simulation.resume(copy, threads=args.threads)
                per = args.per or 50
                k = per * sim.gas.substeps
                runs[name] = (sim, lambda s=sim, k=k: s.step_once(k), per)
            runs[name][1]()  # compile or load the caches
        times = {name: [] for name in runs}
        for r in range(args.bursts):
            for name in (("base", "tree") if r % 2 == 0 else ("tree", "base")):
                t0 = time.perf_counter()
                runs[name][1]()
                times[name].append(time.perf_counter() - t0)
        unit = "particle-steps/s" if args.problem == "bed10k" else "ms per gas step"
        for name, ts in times.items():
            work = runs[name][2]
            vals = sorted((work / t) if args.problem == "bed10k" else (1e3 * t / work) for t in ts)
            best = vals[-1] if args.problem == "bed10k" else vals[0]
            print(f"{name:5s} ({args.base if name == 'base' else 'working tree'}): total {sum(ts):.2f} s, "
                  f"{unit} median {vals[len(vals) // 2]:.4g}, best {best:.4g}")
        a, b = (runs[n][0] for n in ("base", "tree"))
        sa, sb = (x.state if hasattr(x, "state") else x for x in (a, b))
        same = all(np.array_equal(getattr(sa, k), getattr(sb, k)) for k in ("position", "velocity", "omega"))
        print(f"same state: {same}")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
