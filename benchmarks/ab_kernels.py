"""The working tree's kernels against another revision's, in one process, on the same problem.

    NUMBA_NUM_THREADS=1 python benchmarks/ab_kernels.py --base 23248a6 --problem bed10k --repeat 10
    NUMBA_NUM_THREADS=2 python benchmarks/ab_kernels.py --base REV --problem coupled --from runs/tj20 \
        --threads 2 --repeat 30
    NUMBA_NUM_THREADS=1 python benchmarks/ab_kernels.py --base HEAD --problem bed10k --repeat 1 --per 2  # quick check

The shared machine's speed drifts by up to 2x within minutes, so timings of two versions taken in
separate runs minutes apart compare badly. Here the package of revision ``--base`` is extracted
(``git archive``) into a temporary folder as ``fluidem_base`` next to the installed ``fluidem``, both
build the same problem, and they advance it in alternating bursts, one burst each per round
(``harness.round_order``), after one untimed burst each (the base's kernels compile there, one to three
minutes at every start, as its copy is temporary). At the end the two states are compared: a change meant to
leave the results bitwise the same must print ``same state: True``.

Problems: ``bed10k`` the 10,000-sphere bench bed of ``fluidem bench`` (``--per`` DEM steps a burst,
default 200; measured: particle-steps per second); ``coupled`` a coupled run resumed from the
checkpoint of ``--from`` (a run directory, e.g. ``fluidem run tsuji-jet-background --out runs/tj20``; copied, not
changed), ``--per`` gas steps a burst (default 50; measured: milliseconds per gas step).

Printed: min, median and max over the rounds of each version, and the working tree's speed-up over
the base as the median of the per-round ratios.
"""
from __future__ import annotations

import argparse
import importlib
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

import harness  # benchmarks/harness.py: this script's folder is first on sys.path

ROOT = Path(__file__).resolve().parent.parent


def base_package(rev: str, where: Path) -> None:
    """src/fluidem of revision ``rev`` as the package ``fluidem_base`` in ``where``."""
    tar = subprocess.run(["git", "-C", str(ROOT), "archive", rev, "src/fluidem"], check=True,
                         capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(where)], input=tar, check=True)
    pkg = where / "fluidem_base"
    (where / "src" / "fluidem").rename(pkg)
    for f in pkg.rglob("*.py"):  # its data files (cases, beds) from its own folder
        text = f.read_text()
        if 'resources.files("fluidem")' in text:
            f.write_text(text.replace('resources.files("fluidem")', 'resources.files("fluidem_base")'))


def drop_unknown_state(restart: Path, mod) -> None:
    """Remove the particle arrays a package does not know (e.g. ``state/ids`` for an older one) from a
    checkpoint copy, so that it resumes a checkpoint written by another version."""
    import h5py

    known = set(importlib.import_module(f"{mod.__name__}.state").ParticleState.__dataclass_fields__)
    with h5py.File(restart, "a") as f:
        for k in list(f.get("state", {})):
            if k not in known:
                del f["state"][k]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--base", required=True, help="the other revision (any git revision)")
    ap.add_argument("--problem", choices=("bed10k", "coupled"), default="bed10k")
    ap.add_argument("--from", dest="run_dir", help="run directory with restart.h5 (problem 'coupled')")
    ap.add_argument("--per", type=int, default=0, help="steps a burst (default 200 DEM steps / 50 gas steps)")
    ap.add_argument("--threads", type=int, default=None,
                    help="threads of the coupled run (default: the case's, one per 1200 particles)")
    harness.add_options(ap, repeat=20)
    a = ap.parse_args(argv)
    if a.problem == "coupled" and not a.run_dir:
        ap.error("--problem coupled needs --from RUN_DIR")
    tmp = Path(tempfile.mkdtemp(prefix="ab_kernels_"))
    try:
        base_package(a.base, tmp)
        sys.path.insert(0, str(tmp))
        mods = {"base": importlib.import_module("fluidem_base"), "tree": importlib.import_module("fluidem")}
        objects, variants = {}, {}
        for name, mod in mods.items():
            if a.problem == "bed10k":
                eng = importlib.import_module(f"{mod.__name__}.bench").load_bed_engine(10000)
                per = a.per or 200
                objects[name] = eng
                variants[name] = harness.timed(lambda e=eng, k=per: e.advance(k))
                work = 10000 * per  # particle-steps a burst
            else:
                copy = tmp / f"run_{name}"
                shutil.copytree(a.run_dir, copy)
                drop_unknown_state(copy / "restart.h5", mod)
                sim = mod.Simulation.resume(copy, threads=a.threads)
                per = a.per or 50
                objects[name] = sim
                variants[name] = harness.timed(lambda s=sim, k=per * sim.gas.substeps: s.advance(k))
                work = per  # gas steps a burst
        seconds = harness.run_rounds(variants, a.repeat, unit="s", warmup=1)
        # the same rounds as rates or per-step times
        if a.problem == "bed10k":
            unit, scale = "particle-steps/s", (lambda t: work / t)
        else:
            unit, scale = "ms per gas step", (lambda t: 1e3 * t / work)
        rounds = harness.Rounds(seconds.names, unit, orders=seconds.orders,
                                values={n: [scale(t) for t in seconds.values[n]] for n in seconds.names},
                                extras={n: [{"burst_s": t} for t in seconds.values[n]] for n in seconds.names})
        print(f"{a.problem}: base {a.base} against the working tree, {a.repeat} rounds of {per} "
              f"{'DEM' if a.problem == 'bed10k' else 'gas'} steps")
        print(rounds.table(label="version"))
        print(f"total: base {sum(seconds.values['base']):.2f} s, tree {sum(seconds.values['tree']):.2f} s")
        print(seconds.ratio_line("base", "tree", label="speed-up of the working tree over the base"))
        sa, sb = (x.state for x in objects.values())
        same = all(np.array_equal(getattr(sa, k), getattr(sb, k)) for k in ("position", "velocity", "omega"))
        print(f"same state: {same}")
        harness.write_json(a.json, {a.problem: rounds}, base=a.base, problem=a.problem, per=per,
                           run_dir=a.run_dir, threads=a.threads, same_state=same)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
