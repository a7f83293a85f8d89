"""Where each thread of a coupled run spends its time: compiled kernels, OpenMP waits, the Python interpreter.

    NUMBA_NUM_THREADS=2 python benchmarks/perf_shares.py runs/tj20/restart.h5 [--case tsuji-jet] [--seconds 8]

Needs Linux ``perf`` (``apt-get install linux-perf``; this machine has it). A child process loads the
checkpoint, warms up (compiled kernels loaded, one short run), then steps the bed; ``perf record -p``
samples it for ``--seconds`` of that stepping only (no start-up), and ``perf report --sort pid,dso``
gives each thread's samples by shared object. Printed as shares of each thread's wall time:
``[JIT]`` is Numba's compiled code, ``libgomp`` OpenMP (a worker spinning or waiting at a barrier,
the main thread waiting for it), ``libpython`` the interpreter. What a second thread does not spend
in ``[JIT]`` is time the step leaves it idle: the serial parts (the gas side) and uneven shares.
"""
from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path

CHILD = """
import os, sys, time
import fluidem as fd
sim = fd.Simulation(fd.load_case(sys.argv[1]))
sim.load_checkpoint(sys.argv[2])
sim.run(until=sim.time + 0.05)
open(sys.argv[3], "w").write(str(os.getpid()))
deadline = time.perf_counter() + float(sys.argv[4])
while time.perf_counter() < deadline:
    sim.run(until=sim.time + 0.05)
"""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("checkpoint", help="restart.h5 of a run of --case")
    ap.add_argument("--case", default="tsuji-jet")
    ap.add_argument("--seconds", type=float, default=8.0, help="seconds of stepping sampled")
    ap.add_argument("--frequency", type=int, default=2000, help="samples per second and thread")
    a = ap.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="perf_shares_"))
    ready, data = tmp / "ready", tmp / "perf.data"
    child = subprocess.Popen([sys.executable, "-c", CHILD, a.case, a.checkpoint, str(ready), str(a.seconds + 4.0)])
    while not ready.exists() or not ready.read_text():
        if child.poll() is not None:
            raise SystemExit("the stepping process ended before it was ready")
        time.sleep(0.1)
    time.sleep(0.5)
    subprocess.run(["perf", "record", "-q", "-F", str(a.frequency), "-o", str(data), "-p", ready.read_text(),
                    "--", "sleep", str(a.seconds)], check=True)
    child.wait()
    report = subprocess.run(["perf", "report", "-i", str(data), "--sort", "pid,dso", "--stdio"],
                            check=True, capture_output=True, text=True).stdout
    per = defaultdict(dict)
    for line in report.splitlines():
        m = re.match(r"\s*([\d.]+)%\s+(\d+):\S+\s+(.+?)\s*$", line)
        if m:
            share, tid, dso = float(m.group(1)), int(m.group(2)), m.group(3)
            dso = "[JIT]" if dso.startswith("[JIT]") else dso
            per[tid][dso] = per[tid].get(dso, 0.0) + share
    main_tid = int(ready.read_text())
    threads = sorted(per, key=lambda t: (t != main_tid, t))
    print(f"{a.case}, {a.seconds:g} s of stepping from {a.checkpoint}, threads {len(threads)}; "
          f"shares of each thread's wall time (all samples: {sum(sum(d.values()) for d in per.values()):.1f} %)")
    for tid in threads:
        total = sum(per[tid].values())
        top = sorted(per[tid].items(), key=lambda kv: -kv[1])[:6]
        name = "main" if tid == main_tid else f"thread {tid}"
        print(f"  {name:14s} " + ", ".join(f"{d} {100 * s / total:.0f} %" for d, s in top))
    os.remove(data)


if __name__ == "__main__":
    main()
