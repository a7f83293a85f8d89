"""fluidem against LAMMPS and LIGGGHTS on the same settled bed, in one script.

    python benchmarks/compare_peers.py --sizes 10000 --threads 1,2 [--install] [--json out.json]

The bed is fluidem's cached settled bed (``fluidem.bench.settled_bed``); the peers
run it through ``benchmarks/peers/run_peers.py`` with the same contact law, time step
and skin (shared/PEERS.md). Prints particle-steps per second of the stepping loop and
the ratio fluidem / peer at equal core counts.

``--repeat R`` runs R rounds, each timing fluidem and then every peer once, so that all
codes meet the same swings of a shared machine (its speed moved by up to 2x within minutes
here). Each code's row is its fastest round; the last column then also gives the median over
the rounds of the per-round ratio (fluidem and the peer timed minutes apart).
"""
from __future__ import annotations

import argparse
import importlib.util
import json
from pathlib import Path

import numba
import numpy as np

from fluidem.bench import load_bed_engine, settled_bed, time_engine


def _peers_module():
    path = Path(__file__).parent / "peers" / "run_peers.py"
    spec = importlib.util.spec_from_file_location("run_peers", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", default="10000")
    ap.add_argument("--threads", default="1,2")
    ap.add_argument("--steps", type=int, default=2000, help="timed steps for every code")
    ap.add_argument("--codes", default="lammps,liggghts")
    ap.add_argument("--install", action="store_true", help="apt-get install the peers if missing")
    ap.add_argument("--json", help="write all rows as JSON")
    ap.add_argument("--repeat", type=int, default=1, help="rounds of all codes, interleaved; the fastest of each")
    a = ap.parse_args()
    peers = _peers_module()
    if a.install:
        peers.install_peers()
    rounds = []  # per round: {(code, n, cores): row}
    for _ in range(max(a.repeat, 1)):
        got = {}
        for n in [int(s) for s in a.sizes.split(",")]:
            bed = settled_bed(n)
            for t in [int(x) for x in a.threads.split(",")]:
                numba.set_num_threads(min(t, numba.config.NUMBA_NUM_THREADS))
                eng = load_bed_engine(n)
                steps, wall = time_engine(eng, a.steps)
                got[("fluidem", n, t)] = {"code": "fluidem", "n_particles": n, "cores": t, "steps": steps,
                                          "particle_steps_per_s": n * steps / wall}
            for r in peers.run_peers(str(bed), a.steps, [int(x) for x in a.threads.split(",")], a.codes.split(",")):
                got[(r["code"], n, r.get("ranks"))] = {
                    "code": r["code"], "n_particles": n, "cores": r.get("ranks"), "steps": r.get("steps"),
                    "particle_steps_per_s": r.get("particle_steps_per_s"), "error": r.get("error")}
        rounds.append(got)
    rows = []
    for key in rounds[0]:
        rates = [g[key]["particle_steps_per_s"] or 0.0 for g in rounds if key in g]
        best = dict(rounds[int(np.argmax(rates))][key])
        best["rounds"] = rates
        if key[0] != "fluidem":
            ours = [g.get(("fluidem", key[1], key[2]), {}).get("particle_steps_per_s") for g in rounds]
            per = [o / r for o, r in zip(ours, rates) if o and r]
            best["median_round_ratio"] = float(np.median(per)) if per else None
        rows.append(best)
    ours = {(r["n_particles"], r["cores"]): r["particle_steps_per_s"] for r in rows if r["code"] == "fluidem"}
    print(f"{'code':10s} {'N':>7s} {'cores':>5s} {'particle-steps/s':>17s} {'fluidem / this':>15s} "
          f"{'median of rounds':>16s}")
    for r in rows:
        rate = r["particle_steps_per_s"]
        if not rate:
            print(f"{r['code']:10s} {r['n_particles']:7d} {str(r['cores']):>5s} {'-':>17s}  {r.get('error', '')}")
            continue
        ratio = ours.get((r["n_particles"], r["cores"]))
        med = r.get("median_round_ratio")
        print(f"{r['code']:10s} {r['n_particles']:7d} {r['cores']:5d} {rate:17.3e} "
              f"{(ratio / rate) if ratio else float('nan'):15.2f} {med if med else float('nan'):16.2f}")
    if a.json:
        Path(a.json).write_text(json.dumps(rows, indent=2) + "\n")


if __name__ == "__main__":
    main()
