"""fluidem against LAMMPS and LIGGGHTS on the same settled bed, in interleaved rounds.

    python benchmarks/compare_peers.py --sizes 10000 --threads 1,2 --steps 2000 --repeat 3 [--install] [--json out.json]

The bed is fluidem's settled dense bed (``fluidem.bench.settled_bed``: the 10,000-sphere bed ships
with the package); the peers run it through ``benchmarks/peers/run_peers.py`` with the same contact
law, time step and skin (shared/PEERS.md; the decks are described in ``benchmarks/peers/README.md``).
Each round times, for every bed size and core count, fluidem (a fresh engine on the bed, 20 untimed
steps, then ``--steps`` timed ones on ``k`` Numba threads) and each peer (``k`` MPI ranks, the loop
time its log reports), in the order of ``harness.round_order``. Printed per code: particle-steps per
second of the stepping loop (min, median, max over the rounds) and fluidem / code at equal core
counts, as the median of the per-round ratios.

A peer that is not installed is named and left out; fluidem is timed all the same. ``--install``
runs ``apt-get install lammps liggghts openmpi-bin`` first (as root, or through sudo).
"""
from __future__ import annotations

import argparse
import importlib.util
import sys
from pathlib import Path

import numba

from fluidem.bench import load_bed_engine, settled_bed, time_engine

import harness  # benchmarks/harness.py: this script's folder is first on sys.path

NAMES = {"lammps": "LAMMPS", "liggghts": "LIGGGHTS"}


def peers_module():
    """``benchmarks/peers/run_peers.py`` as a module."""
    path = Path(__file__).resolve().parent / "peers" / "run_peers.py"
    spec = importlib.util.spec_from_file_location("run_peers", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def available_peers(peers, codes, cores) -> tuple[list[str], list[str]]:
    """(codes that can run, one message per code or core count that cannot)."""
    ok, missing = [], []
    for code in codes:
        if code not in peers.CODES:
            missing.append(f"{code}: unknown code (known: {', '.join(peers.CODES)})")
        elif peers.find_binary(code) is None:
            missing.append(f"{NAMES[code]} is not installed (looked for {', '.join(peers.BINARIES[code])} on PATH "
                           f"and ${peers.BIN_ENV[code]}): not timed. Install it with: apt-get install -y "
                           f"--no-install-recommends {' '.join(peers.APT_PACKAGES)} (or pass --install)")
        else:
            ok.append(code)
    if ok and any(k > 1 for k in cores) and peers.mpi_launcher(2) is None:
        missing.append("no mpirun/mpiexec on PATH: the peers run on one core only (apt-get install openmpi-bin)")
    return ok, missing


def fluidem_variant(n: int, threads: int, steps: int):
    def measure() -> dict:
        numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
        eng = load_bed_engine(n)
        done, wall = time_engine(eng, steps)
        return {"value": n * done / wall, "steps": done, "wall_s": wall}

    return measure


def peer_variant(peers, code: str, bed: dict, steps: int, ranks: int, errors: dict):
    def measure():
        row = peers.run_one(code, bed, steps, ranks)
        if "error" in row:
            errors.setdefault(code, row["error"])
            return None
        extra = {k: row[k] for k in ("loop_time_s", "other_busy_cores", "neighbor_builds") if k in row}
        return {"value": row["particle_steps_per_s"], **extra}

    return measure


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", default="10000", help="bed sizes (10000 or multiples of it)")
    ap.add_argument("--threads", default="1,2", help="core counts: Numba threads for fluidem, MPI ranks for the peers")
    ap.add_argument("--steps", type=int, default=2000, help="timed steps for every code")
    ap.add_argument("--codes", default="lammps,liggghts", help="peer codes")
    ap.add_argument("--install", action="store_true", help="apt-get install the peers if missing")
    harness.add_options(ap, repeat=3)
    a = ap.parse_args(argv)
    peers = peers_module()
    sizes = [int(s) for s in a.sizes.split(",") if s]
    cores = [int(t) for t in a.threads.split(",") if t]
    codes = [c.strip().lower() for c in a.codes.split(",") if c.strip()]
    if a.install:
        print("[compare_peers] " + peers.install_peers(), file=sys.stderr)
    codes, missing = available_peers(peers, codes, cores)
    for line in missing:
        print(line, flush=True)
    if any(k > numba.config.NUMBA_NUM_THREADS for k in cores):
        print(f"note: Numba has {numba.config.NUMBA_NUM_THREADS} threads; fluidem runs on at most that many",
              flush=True)
    one_core_only = peers.mpi_launcher(2) is None
    measurements, errors, summary = {}, {}, []
    for n in sizes:
        bed_path = settled_bed(n)
        bed = peers.load_bed(bed_path)
        for k in cores:
            variants = {"fluidem": fluidem_variant(n, k, a.steps)}
            for code in codes:
                if k == 1 or not one_core_only:
                    variants[NAMES[code]] = peer_variant(peers, code, bed, a.steps, k, errors)
            rounds = harness.run_rounds(variants, a.repeat, unit="particle-steps/s")
            measurements[f"N={n} cores={k}"] = rounds
            print(f"\n{n} spheres, {k} core{'s' if k > 1 else ''}, {a.steps} steps, {a.repeat} rounds")
            print(rounds.table(label="code"))
            for name in rounds.names[1:]:
                print(rounds.ratio_line("fluidem", name))
            for name in rounds.names:
                s = rounds.stats(name)
                per = harness.spread(rounds.ratios("fluidem", name))
                summary.append([name, n, k, s["n"], s["min"], s["median"], s["max"],
                                None if name == "fluidem" else per["median"],
                                None if name == "fluidem" else per["min"],
                                None if name == "fluidem" else per["max"]])
    for code, err in errors.items():
        print(f"\n{NAMES[code]} failed: {err}", file=sys.stderr)
    print("\nparticle-steps per second of the stepping loop; fluidem / code: per-round ratios at equal cores")
    print(harness.format_table(["code", "N", "cores", "rounds", "min", "median", "max",
                                "fluidem/code median", "min", "max"], summary))
    harness.write_json(a.json, measurements, steps=a.steps, codes=codes, not_timed=missing, errors=errors)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
