#!/usr/bin/env bash
# The GPU engine on a machine with an NVIDIA GPU: its tests run on the device (no simulator), then the
# dense-bed rows of `fluidem bench --device gpu` (1e5, 1e6, 1e7 Hertz-Mindlin spheres) and the CPU's
# one-core rate of the same bed for comparison. Results go to $OUT (default ./gpu-check-out):
#   env.txt         GPU, driver, Python and library versions
#   ptx.log         every kernel compiled for the GPU's compute capability
#   tests.log       python3 -m pytest tests/gpu (forces, trajectories, checkpoints against the CPU engine)
#   bench_gpu.json  bench_gpu.log   the GPU rows
#   bench_cpu.json  bench_cpu.log   the CPU rows (the 100,000-sphere bed, one thread)
#   coupled.txt     the coupled tsuji-jet bed (2400 spheres, 15 x 45 gas cells) over 0.2 s: the GPU engine with
#                   the coupling's particle side on the device, the same with it on the host
#                   (coupling.gpu_exchange = "host"), and the CPU engine on one core; wall time, start-up,
#                   particle/gas split and warm rate from each run's summary.json (tsuji_*/, tsuji_*.log)
#   coupled3d.txt   the 3D coupled bubbling-3d bed (9240 spheres, 15 x 40 x 3 gas cells, exact-volume voidage)
#                   over 0.005 s (50 gas steps): the GPU engine with the 3D coupling's particle side on the
#                   device, and with it on the host (coupling.gpu_exchange = "host"); the same columns
#                   (bubbling3d_*/, bubbling3d_*.log)
#
# Needs Python 3.12 with numpy, numba, numba-cuda, scipy, h5py and matplotlib (the device image has them)
# plus pydantic and tomli-w. Where those two are missing and nothing can be downloaded, carry them as
# wheels in .whl/ (ignored by git) from a machine that reaches PyPI, in the repository root:
#
#   echo /.whl/ >> .git/info/exclude
#   python3 -m pip download --no-deps --only-binary=:all: --python-version 3.12 --implementation cp \
#       --platform manylinux_2_17_x86_64 --platform manylinux2014_x86_64 -d .whl \
#       pydantic pydantic-core annotated-types typing-inspection tomli-w
#
# (one version of each; pydantic-core must be the one pydantic pins). The script installs .whl/*.whl into
# /tmp/site when the folder exists. It takes about 9-12 minutes, most of it compiling the CPU kernels once
# and building the 1e7 bed; run it from the repository root:
#
#   bash benchmarks/gpu_device_check.sh
set -uo pipefail
cd "$(dirname "$0")/.."
OUT=${OUT:-$PWD/gpu-check-out}
mkdir -p "$OUT"
export PYTHONUNBUFFERED=1
if [ -d .whl ] && ls .whl/*.whl >/dev/null 2>&1; then
    python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site \
        .whl/*.whl || exit 1
    export PYTHONPATH=/tmp/site
fi
export PYTHONPATH="$PWD/src${PYTHONPATH:+:$PYTHONPATH}"
unset NUMBA_ENABLE_CUDASIM

{
    nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv 2>&1
    python3 - <<'EOF'
import numpy as np
if not hasattr(np, "row_stack"):
    np.row_stack = np.vstack
import platform, numba
from numba import cuda
print("python", platform.python_version(), "numpy", np.__version__, "numba", numba.__version__)
try:
    import numba_cuda
    print("numba-cuda", numba_cuda.__version__)
except ImportError:
    print("numba-cuda not installed (numba's own numba.cuda)")
print("cuda.is_available()", cuda.is_available())
if cuda.is_available():
    d = cuda.get_current_device()
    print("device", d.name, "compute capability", d.compute_capability)
EOF
} 2>&1 | tee "$OUT/env.txt"

cc=$(python3 -c "import numpy as np
if not hasattr(np, 'row_stack'): np.row_stack = np.vstack
from numba import cuda; print(*cuda.get_current_device().compute_capability)" 2>/dev/null || echo "9 0")
python3 tests/_helpers/gpu_ptx.py $cc 2>&1 | tee "$OUT/ptx.log"

python3 -m pytest -q -p no:cacheprovider tests/gpu 2>&1 | tee "$OUT/tests.log"

python3 -m fluidem bench --device gpu --sizes 100000,1000000,10000000 --json "$OUT/bench_gpu.json" 2>&1 \
    | tee "$OUT/bench_gpu.log"

python3 -m fluidem bench --sizes 100000 --threads 1 --no-gas --no-coupled --no-hard-sphere \
    --json "$OUT/bench_cpu.json" 2>&1 | tee "$OUT/bench_cpu.log"

# the coupled bed: GPU engine with the device coupling, with the host coupling, CPU engine on one core
for mode in device host; do
    python3 -m fluidem run tsuji-jet --until 0.2 --device gpu --set coupling.gpu_exchange=$mode -q \
        --out "$OUT/tsuji_gpu_$mode" > "$OUT/tsuji_gpu_$mode.log" 2>&1
done
python3 -m fluidem run tsuji-jet --until 0.2 --device cpu --threads 1 -q --out "$OUT/tsuji_cpu" \
    > "$OUT/tsuji_cpu.log" 2>&1
python3 - "$OUT" <<'EOF' 2>&1 | tee "$OUT/coupled.txt"
import json, sys
from pathlib import Path
out = Path(sys.argv[1])
print("tsuji-jet, 0.2 s simulated (1000 gas steps of 14 DEM steps, 2400 spheres)")
print(f"{'run':<18}{'wall_s':>9}{'startup_s':>11}{'particle_s':>12}{'gas_s':>9}{'warm particle-steps/s':>24}")
for name in ("tsuji_gpu_device", "tsuji_gpu_host", "tsuji_cpu"):
    f = out / name / "summary.json"
    if not f.exists():
        print(f"{name:<18} no summary.json (see {name}.log)")
        continue
    s = json.loads(f.read_text())
    nan = float("nan")
    print(f"{name:<18}{s['wall_time_s']:>9.2f}{s.get('startup_s') or nan:>11.2f}{s['particle_time_s']:>12.2f}"
          f"{s['gas_time_s']:>9.2f}{s.get('particle_steps_per_s') or nan:>24.4g}")
EOF

# the 3D coupled bed: GPU engine with the 3D coupling's particle side on the device, and on the host
for mode in device host; do
    python3 -m fluidem run bubbling-3d --until 0.005 --device gpu --set coupling.gpu_exchange=$mode -q \
        --out "$OUT/bubbling3d_gpu_$mode" > "$OUT/bubbling3d_gpu_$mode.log" 2>&1
done
python3 - "$OUT" <<'EOF' 2>&1 | tee "$OUT/coupled3d.txt"
import json, sys
from pathlib import Path
out = Path(sys.argv[1])
print("bubbling-3d, 0.005 s simulated (50 gas steps on 15 x 40 x 3 cells, 9240 spheres)")
print(f"{'run':<24}{'wall_s':>9}{'startup_s':>11}{'particle_s':>12}{'gas_s':>9}{'warm particle-steps/s':>24}")
for name in ("bubbling3d_gpu_device", "bubbling3d_gpu_host"):
    f = out / name / "summary.json"
    if not f.exists():
        print(f"{name:<24} no summary.json (see {name}.log)")
        continue
    s = json.loads(f.read_text())
    nan = float("nan")
    print(f"{name:<24}{s['wall_time_s']:>9.2f}{s.get('startup_s') or nan:>11.2f}{s['particle_time_s']:>12.2f}"
          f"{s['gas_time_s']:>9.2f}{s.get('particle_steps_per_s') or nan:>24.4g}")
EOF
