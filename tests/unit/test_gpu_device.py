"""Choosing the particle engine's device: the case key ``device``, ``fluidem run --device``, refusals, and the
GPU tests (``tests/gpu``) run under the CUDA simulator in a subprocess.

The simulator must be switched on (``NUMBA_ENABLE_CUDASIM=1``) before Numba is imported, which this
process did long ago, so ``test_gpu_engine_under_the_cuda_simulator`` runs ``pytest tests/gpu`` in a
process of its own. On a machine with a GPU, ``python3 -m pytest tests/gpu`` runs them on the device.
"""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from fluidem.case import load_case
from fluidem.cli import main
from fluidem.errors import CaseError
from fluidem.particles import engine_for
from fluidem.particles.softsphere import SoftSphereEngine
from fluidem.particles.softsphere_gpu import choose_device, cuda_available, gpu_refusals

ROOT = Path(__file__).resolve().parents[2]
SIMULATOR_TIMEOUT = 900  # [s] the GPU tests under the simulator take 1-2 minutes on two cores


def test_device_key_defaults_to_cpu_and_is_checked():
    assert load_case("pour").device == "cpu"
    assert load_case("pour", {"device": "auto"}).device == "auto"
    with pytest.raises(CaseError, match="device") as err:
        load_case("pour", {"device": "tpu"})
    assert "'cpu', 'gpu' or 'auto'" in str(err.value) or "cpu" in str(err.value)


def test_hard_spheres_on_the_gpu_are_refused_by_name():
    case = load_case("hoomans-pour", {"device": "gpu"})
    assert any("hard_sphere" in r for r in gpu_refusals(case))
    with pytest.raises(CaseError, match="device = 'gpu'.*hard_sphere"):
        engine_for(case)


def test_a_gas_coupled_case_runs_on_the_gpu():
    """The particle side of the coupling runs on the host with the particles fetched once a gas step
    (tests/gpu: ``test_coupled_run_matches_cpu``): a [gas] section is no refusal."""
    assert gpu_refusals(load_case("tsuji-jet", {"device": "gpu"})) == []


def test_auto_falls_back_to_the_cpu():
    """``auto`` keeps an unsupported case on the CPU, and a supported one where no GPU is found."""
    assert choose_device(load_case("hoomans-pour", {"device": "auto"})) == "cpu"
    if not cuda_available():
        assert isinstance(engine_for(load_case("pour", {"device": "auto"})), SoftSphereEngine)
        with pytest.raises(CaseError, match="no CUDA GPU"):
            choose_device(load_case("pour", {"device": "gpu"}))


def test_run_device_flag_refuses_with_exit_status_2_and_writes_nothing(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["run", "hoomans-pour", "--device", "gpu", "--out", str(out)]) == 2
    assert "hard_sphere" in capsys.readouterr().err
    assert not out.exists()


def test_bench_device_gpu_without_a_gpu_is_a_clear_error(capsys):
    if cuda_available():
        pytest.skip("a GPU is present")
    assert main(["bench", "--device", "gpu", "--sizes", "100000"]) == 2
    assert "no CUDA GPU" in capsys.readouterr().err


def _simulator_works() -> str | None:
    """None if numba.cuda's simulator imports in a fresh process, else why not."""
    env = dict(os.environ, NUMBA_ENABLE_CUDASIM="1")
    r = subprocess.run([sys.executable, "-c", "from numba import cuda; assert cuda.is_available()"], env=env,
                       capture_output=True, text=True, timeout=120)
    return None if r.returncode == 0 else (r.stderr.strip().splitlines() or ["failed"])[-1]


def test_gpu_engine_under_the_cuda_simulator():
    """tests/gpu (forces, trajectories, checkpoints against the CPU engine) in a process with the simulator."""
    if cuda_available():
        pytest.skip("numba.cuda works in this process: tests/gpu run here directly")
    why = _simulator_works()
    if why is not None:
        pytest.skip(f"the CUDA simulator is not available: {why}")
    env = dict(os.environ, NUMBA_ENABLE_CUDASIM="1")
    r = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(ROOT / "tests" / "gpu")],
                       cwd=ROOT, env=env, capture_output=True, text=True, timeout=SIMULATOR_TIMEOUT)
    tail = "\n".join((r.stdout + r.stderr).strip().splitlines()[-40:])
    assert r.returncode == 0, tail
    assert " passed" in tail and "skipped" not in tail.splitlines()[-1], tail


def test_gpu_kernels_compile_to_ptx():
    """numba-cuda types and compiles every kernel for sm_90 (H100/H200) without a GPU, where numba-cuda, NVVM
    and NVRTC are installed (``pip install numba-cuda nvidia-nvvm nvidia-cuda-nvrtc``); the simulator does
    not check types. Run in a subprocess: numba-cuda replaces numba.cuda at Numba's import."""
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"))
    env.pop("NUMBA_ENABLE_CUDASIM", None)
    probe = subprocess.run([sys.executable, "-c", "import numba_cuda; from numba.cuda.cudadrv import nvvm; "
                            "nvvm.NVVM()"], env=env, capture_output=True, text=True, timeout=120)
    if probe.returncode != 0:
        pytest.skip("numba-cuda with NVVM is not installed: " + ((probe.stderr.strip().splitlines() or ["?"])[-1]))
    r = subprocess.run([sys.executable, str(ROOT / "tests" / "_helpers" / "gpu_ptx.py"), "9", "0"], env=env,
                       capture_output=True, text=True, timeout=SIMULATOR_TIMEOUT)
    assert r.returncode == 0, (r.stdout + r.stderr)[-3000:]
    assert r.stdout.count("characters of PTX") == 32, r.stdout  # 8 of the particle step, 7 + 7 + 5 + 5 of the coupling


def test_contact_physics_the_gpu_path_lacks_is_refused_by_name():
    """JKR adhesion, rolling resistance and the Hertzian linear variant run on the CPU engine only."""
    from fluidem.case import load_case
    from fluidem.particles.softsphere_gpu import gpu_refusals

    assert gpu_refusals(load_case("pour")) == []
    rolling = gpu_refusals(load_case("pour", {"particles.contact.rolling_friction": 0.2}))
    assert rolling == ["particles.contact.rolling_friction = 0.2 (rolling resistance)"]
    hertzian = gpu_refusals(load_case("pour", {"particles.contact.nonlinearity": "hertzian"}))
    assert hertzian == ["particles.contact.nonlinearity = 'hertzian' (Sun 2007's Hertzian linear law)"]


def test_coupling_options_the_device_exchange_lacks_keep_it_on_the_host():
    """The GPU engine's coupling runs its particle side on the device for the default options of the built-in
    2D gas cases (``tsuji-jet``: centroid map, 'particle' exchange, gidaspow); each option without a device
    kernel is named, and ``coupling.gpu_exchange = 'host'`` asks for the host path."""
    from types import SimpleNamespace

    from fluidem.coupling.exchange_gpu import refusals

    def coupling(case):
        c = case.coupling
        return SimpleNamespace(options=c, exchange=c.momentum_exchange, mapping=c.voidage,
                               polydisperse=c.resolved_polydisperse([4e-3]))

    assert refusals(coupling(load_case("tsuji-jet"))) == []
    assert refusals(coupling(load_case("tsuji-jet", {"coupling.drag_update": "frozen",
                                                     "coupling.boundary_faces": "exchange",
                                                     "coupling.voidage.velocity_weighting": "volume",
                                                     "coupling.voidage.smoothing_width": 0.01}))) == []
    assert refusals(coupling(load_case("tsuji-jet", {"coupling.gpu_exchange": "host"}))) == [
        "coupling.gpu_exchange = 'host'"]
    assert refusals(coupling(load_case("goldschmidt-sun-method"))) == []  # the "cell" exchange on the device too
    # "cell_beta" too: its cell β as "cell", each particle's drag by ``_cell_cuda.gas_forces``
    assert refusals(coupling(load_case("tsuji-jet", {"coupling.momentum_exchange": "cell_beta"}))) == []
    for method in ("area", "area_volume"):  # the exact disc areas of Hoomans 1996 §3.4 on the device too
        assert refusals(coupling(load_case("tsuji-jet", {"coupling.voidage.method": method}))) == []
    assert refusals(coupling(load_case("bubbling-pseudo2d"))) == []
    assert refusals(coupling(load_case("tsuji-jet", {"coupling.polydisperse": "sauter_y2"}))) == []
