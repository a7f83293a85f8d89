"""What a first run spends compiling: Numba's compile events of a short run of a case on an empty cache.

    python benchmarks/compile_time.py --case pour --until 0.001
    python benchmarks/compile_time.py --case bubbling-3d --until 0.0005 --top 30

The run (``fluidem run CASE --until UNTIL --threads THREADS --quiet``) goes in a child process whose
``NUMBA_CACHE_DIR`` is a new empty folder, so that every kernel it needs is compiled, however warm this
machine's cache is. Numba reports each compilation (``numba:compile`` events, ``numba.core.event``) with its
start and end; a compilation that triggers others (a kernel and the functions it calls) contains theirs.
Printed: the run's wall time to its first step (``startup_s`` of its summary), the compile time summed, the
``--top`` functions by exclusive compile time (their own, without the nested compilations), and every
package function compiled more than once with the argument positions whose types differ: a constant
argument in a call between compiled functions is a literal type (``Literal[int](0)``) and compiles the
callee once more (``tests/unit/test_kernel_literals.py`` guards the calls it can see in the sources).
"""
from __future__ import annotations

import argparse
import collections
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def child(argv: list[str]) -> int:
    """Runs ``fluidem`` with ``argv`` under a compile-event listener; prints one JSON line of the records."""
    from numba.core import event

    stack, records = [], []

    class Listener(event.Listener):
        def on_start(self, e):
            d = e.data["dispatcher"].py_func
            stack.append([f"{d.__module__}.{d.__qualname__}", str(e.data.get("args")), time.perf_counter(), 0.0])

        def on_end(self, e):
            name, args, t0, nested = stack.pop()
            dt = time.perf_counter() - t0
            records.append((name, args, dt, dt - nested))
            if stack:
                stack[-1][3] += dt

    event.register("numba:compile", Listener())
    from fluidem.cli import main

    t0 = time.perf_counter()
    rc = main(argv)
    print("\n" + json.dumps({"rc": rc, "wall_s": time.perf_counter() - t0, "records": records}))
    return 0


def _split_args(sig: str) -> list[str]:
    """The top-level argument types of a signature's string form."""
    out, depth, cur = [], 0, ""
    for ch in sig.strip()[1:-1]:
        if ch in "([":
            depth += 1
        elif ch in ")]":
            depth -= 1
        if ch == "," and depth == 0:
            out.append(cur.strip())
            cur = ""
        else:
            cur += ch
    if cur.strip():
        out.append(cur.strip())
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--case", default="pour", help="built-in case or case file")
    ap.add_argument("--until", default="0.001", help="simulated seconds of the run [s]")
    ap.add_argument("--threads", default="1", help="compute threads of the run")
    ap.add_argument("--top", type=int, default=20, help="functions listed by exclusive compile time")
    ap.add_argument("--child", nargs=argparse.REMAINDER, help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.child is not None:
        return child(a.child)
    with tempfile.TemporaryDirectory() as tmp:
        env = dict(os.environ, NUMBA_CACHE_DIR=str(Path(tmp) / "cache"))
        out = Path(tmp) / "run"
        res = subprocess.run([sys.executable, __file__, "--child", "run", a.case, "--until", a.until, "--threads",
                              a.threads, "--quiet", "--out", str(out)], env=env, capture_output=True, text=True)
        if res.returncode != 0 or not res.stdout.strip():
            sys.stderr.write(res.stderr)
            return 1
        data = json.loads(res.stdout.strip().splitlines()[-1])
        summary = json.loads((out / "summary.json").read_text()) if (out / "summary.json").exists() else {}
    records = data["records"]
    own = collections.Counter()
    sigs = collections.defaultdict(list)
    for name, args, _, exclusive in records:
        own[name] += exclusive
        sigs[name].append(args)
    total = sum(r[3] for r in records)
    print(f"case {a.case}, --until {a.until}, {a.threads} thread(s), empty cache: run {data['wall_s']:.1f} s, "
          f"to its first step {summary.get('startup_s', float('nan')):.1f} s; compiling {total:.1f} s in "
          f"{len(records)} compilations of {len(own)} functions")
    print(f"\n{'exclusive s':>11s} {'count':>5s}  function")
    for name, t in own.most_common(a.top):
        print(f"{t:11.2f} {len(sigs[name]):5d}  {name}")
    print("\npackage functions compiled more than once (argument positions whose types differ):")
    for name, ss in sorted(sigs.items()):
        if len(ss) < 2 or not name.startswith("fluidem."):
            continue
        parts = [_split_args(s) for s in ss]
        diff = {i: sorted({p[i] if i < len(p) else "-" for p in parts})
                for i in range(max(map(len, parts))) if len({p[i] if i < len(p) else "-" for p in parts}) > 1}
        shown = "; ".join(f"{i}: " + " | ".join(re.sub(r"\s+", " ", v)[:40] for v in vs) for i, vs in diff.items())
        print(f"{own[name]:8.2f} s {len(ss)}x  {name}  [{shown}]")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
